#include "mocap/initialisation.h"

#include <Eigen/SVD>
#include <algorithm>
#include <functional>
#include <map>

#include "mocap/kinematics.h"
#include "mocap/so3.h"

namespace mocap {
namespace {

// A site moves (nearly) rigidly with the torso when it lies on the pelvis, the spine or
// a clavicle, or at the origin of a bone hanging from them (hips, shoulders).
bool IsTorsoBone(const Skeleton& skeleton, int b) {
  const std::string& name = skeleton.bone(b).name;
  return b == 0 || name.rfind("spine", 0) == 0 || name.rfind("clavicle", 0) == 0;
}

bool IsTorsoSite(const Skeleton& skeleton, const Site& site) {
  if (IsTorsoBone(skeleton, site.bone)) return true;
  const int parent = skeleton.bone(site.bone).parent;
  return site.offset.norm() < 1e-9 && parent >= 0 && IsTorsoBone(skeleton, parent);
}

// Rotation R and translation t minimising sum |dst - (R src + t)|^2 (Kabsch).
bool RigidFit(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
              Eigen::Matrix3d* r) {
  if (src.size() < 3) return false;
  Eigen::Vector3d cs = Eigen::Vector3d::Zero(), cd = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < src.size(); ++i) {
    cs += src[i];
    cd += dst[i];
  }
  cs /= src.size();
  cd /= src.size();
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < src.size(); ++i) h += (src[i] - cs) * (dst[i] - cd).transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  // Degenerate (collinear) point sets leave the rotation undetermined.
  if (svd.singularValues()(1) < 1e-3 * svd.singularValues()(0)) return false;
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  *r = svd.matrixV() * d * svd.matrixU().transpose();
  return true;
}

// A keypoint's site in the rest pose (world frame).
using RestSite = std::function<Eigen::Vector3d(int)>;

// Root rotation that turns the rest pose (facing +x, up +z) to face the camera.
Eigen::Matrix3d FacingCamera(const Camera& camera, const Eigen::Vector3d& at) {
  Eigen::Vector3d forward = camera.Center() - at;
  forward.z() = 0.0;
  if (forward.norm() < 1e-6) return Eigen::Matrix3d::Identity();
  forward.normalize();
  Eigen::Matrix3d r;
  r.col(0) = forward;
  r.col(2) = Eigen::Vector3d::UnitZ();
  r.col(1) = r.col(2).cross(r.col(0));
  return r;
}

}  // namespace

bool TriangulatePoint(const Rig& rig, const std::vector<Detection>& views, Eigen::Vector3d* x) {
  if (views.size() < 2) return false;
  Eigen::MatrixXd a(2 * views.size(), 4);
  for (size_t i = 0; i < views.size(); ++i) {
    const Camera& c = rig.cameras[views[i].camera];
    Eigen::Matrix<double, 3, 4> p;
    p << c.rotation, c.translation;
    const Eigen::Vector2d uv = c.Undistort(views[i].pixel);
    const double w = views[i].confidence;
    a.row(2 * i) = w * (uv.x() * p.row(2) - p.row(0));
    a.row(2 * i + 1) = w * (uv.y() * p.row(2) - p.row(1));
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullV);
  const Eigen::Vector4d h = svd.matrixV().col(3);
  if (std::abs(h(3)) < 1e-12) return false;
  const Eigen::Vector3d p = h.head<3>() / h(3);
  for (const Detection& v : views) {
    const Camera& c = rig.cameras[v.camera];
    if ((c.rotation * p + c.translation).z() <= Camera::kMinDepth) return false;
  }
  if (!p.allFinite()) return false;
  *x = p;
  return true;
}

namespace {

// The rest-pose sites and the triangulated world points of the keypoints seen in two or
// more views: all of them, and those moving with the torso.
struct SitePairs {
  std::vector<Eigen::Vector3d> torso_rest, torso_world, all_rest, all_world;
};

SitePairs TriangulateSites(const Skeleton& skeleton, const Rig& rig, const KeypointLayout& layout,
                           const std::vector<Detection>& detections, const RestSite& rest_site) {
  std::map<int, std::vector<Detection>> by_keypoint;
  for (const Detection& d : detections) by_keypoint[d.keypoint].push_back(d);
  SitePairs out;
  for (const auto& [k, views] : by_keypoint) {
    Eigen::Vector3d x;
    if (!TriangulatePoint(rig, views, &x)) continue;
    out.all_rest.push_back(rest_site(k));
    out.all_world.push_back(x);
    if (IsTorsoSite(skeleton, layout.sites[k])) {
      out.torso_rest.push_back(out.all_rest.back());
      out.torso_world.push_back(x);
    }
  }
  return out;
}

// The root's orientation from an IMU on the root bone; false when none has a reading.
bool RootFromImus(const std::vector<ImuSite>& imus,
                  const std::vector<std::optional<Eigen::Matrix3d>>& imu_world,
                  Eigen::Matrix3d* root) {
  for (size_t i = 0; i < imus.size(); ++i) {
    if (imus[i].bone == 0 && imu_world[i]) {
      *root = *imu_world[i] * imus[i].mount.transpose();
      return true;
    }
  }
  return false;
}

// One view: the body's place along the rays of the camera that sees most keypoints, its
// depth from the spread of the detections against the rest-pose sites; the root facing
// that camera unless known. False when the detections have no spread.
bool PlaceFromOneView(const Rig& rig, const std::vector<Detection>& detections,
                      const RestSite& rest_site, bool root_known, Eigen::Matrix3d* root,
                      Eigen::Vector3d* at, Eigen::Vector3d* rest_centroid) {
  std::map<int, std::vector<const Detection*>> by_camera;
  for (const Detection& d : detections) by_camera[d.camera].push_back(&d);
  const auto best = std::max_element(by_camera.begin(), by_camera.end(), [](auto& a, auto& b) {
    return a.second.size() < b.second.size();
  });
  const Camera& cam = rig.cameras[best->first];
  const auto& dets = best->second;
  std::vector<double> depths;
  Eigen::Vector2d centroid(0, 0);
  *rest_centroid = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < dets.size(); ++i) {
    centroid += cam.Undistort(dets[i]->pixel);
    *rest_centroid += rest_site(dets[i]->keypoint);
    for (size_t j = i + 1; j < dets.size(); ++j) {
      const double img = (cam.Undistort(dets[i]->pixel) - cam.Undistort(dets[j]->pixel)).norm();
      const double body = (rest_site(dets[i]->keypoint) - rest_site(dets[j]->keypoint)).norm();
      if (img > 1e-4) depths.push_back(body / img);
    }
  }
  if (depths.empty()) return false;
  std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
  const double depth = depths[depths.size() / 2];
  centroid /= dets.size();
  *rest_centroid /= dets.size();
  *at = cam.Center() +
        depth * cam.rotation.transpose() * Eigen::Vector3d(centroid.x(), centroid.y(), 1.0);
  if (!root_known) *root = FacingCamera(cam, *at);
  return true;
}

// Each bone with an IMU reading turned to it, parents first.
void BonesFromImus(const Skeleton& skeleton, const std::vector<ImuSite>& imus,
                   const std::vector<std::optional<Eigen::Matrix3d>>& imu_world,
                   Eigen::VectorXd* theta) {
  for (int b = 1; b < skeleton.num_bones(); ++b) {
    for (size_t i = 0; i < imus.size(); ++i) {
      if (imus[i].bone != b || !imu_world[i]) continue;
      BodyPose pose;
      ForwardKinematics(skeleton, theta->data(), &pose);
      const Eigen::Matrix3d target = *imu_world[i] * imus[i].mount.transpose();
      theta->segment<3>(Skeleton::RotationIndex(b)) =
          Log(pose.rotation[skeleton.bone(b).parent].transpose() * target);
      break;
    }
  }
}

}  // namespace

InitialPose EstimateInitialPose(const Skeleton& skeleton, const Rig& rig,
                                const KeypointLayout& layout, const std::vector<ImuSite>& imus,
                                const std::vector<Detection>& detections,
                                const std::vector<std::optional<Eigen::Matrix3d>>& imu_world) {
  InitialPose out;
  out.theta = Eigen::VectorXd::Zero(skeleton.pose_dim());
  BodyPose rest;
  ForwardKinematics(skeleton, out.theta.data(), &rest);
  const RestSite rest_site = [&](int k) {
    const Site& s = layout.sites[k];
    return Eigen::Vector3d(rest.position[s.bone] + s.offset);
  };
  const SitePairs sites = TriangulateSites(skeleton, rig, layout, detections, rest_site);
  Eigen::Matrix3d root = Eigen::Matrix3d::Identity();
  bool root_known = RootFromImus(imus, imu_world, &root);
  if (!root_known) root_known = RigidFit(sites.torso_rest, sites.torso_world, &root);

  // Root position: x = R q + t for rest sites q; theta_t = t - offset_0 + R offset_0.
  const Eigen::Vector3d offset0 = skeleton.bone(0).offset;
  const bool torso = !sites.torso_world.empty();
  const auto& rest_pts = torso ? sites.torso_rest : sites.all_rest;
  const auto& world_pts = torso ? sites.torso_world : sites.all_world;
  Eigen::Vector3d at, rest_centroid;
  if (!world_pts.empty()) {
    Eigen::Vector3d t = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < world_pts.size(); ++i) t += world_pts[i] - root * rest_pts[i];
    t /= world_pts.size();
    out.theta.head<3>() = t - offset0 + root * offset0;
    out.position_known = true;
  } else if (!detections.empty() &&
             PlaceFromOneView(rig, detections, rest_site, root_known, &root, &at, &rest_centroid)) {
    out.theta.head<3>() = at - root * rest_centroid - offset0 + root * offset0;
    out.position_known = true;
  }
  out.theta.segment<3>(3) = Log(root);
  BonesFromImus(skeleton, imus, imu_world, &out.theta);
  return out;
}

}  // namespace mocap
