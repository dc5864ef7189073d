#include "synthetic_scene.h"

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>
#include <stdexcept>

#include "mocap/so3.h"

namespace mocap::testing {

std::string DataPath(const std::string& relative) {
  return std::string(MOCAP_DATA_DIR) + "/" + relative;
}

Scene MakeScene(int cameras, const std::string& layout) {
  Scene s;
  std::string error;
  EXPECT_TRUE(LoadSkeletonJson(DataPath("skeleton_default.json"), &s.skeleton, &error)) << error;
  KeypointLayout raw;
  EXPECT_TRUE(
      LoadKeypointLayoutJson(DataPath("layouts/" + layout + ".json"), s.skeleton, &raw, &error))
      << error;
  s.layout = raw.ScaledTo(s.skeleton);
  EXPECT_TRUE(LoadImuSitesJson(DataPath("imus13.json"), s.skeleton, &s.imus, &error)) << error;
  for (size_t i = 0; i < s.imus.size(); ++i) {  // mounting 10-20 deg, reference heading offsets
    s.imus[i].mount = Exp(Eigen::Vector3d(0.1, -0.2, 0.15 + 0.01 * i));
    s.imus[i].reference = Exp(Eigen::Vector3d(0, 0, 0.3 - 0.05 * i));
  }
  for (int c = 0; c < cameras; ++c) {
    Camera cam;
    cam.name = "cam" + std::to_string(c);
    cam.width = 1920;
    cam.height = 1080;
    cam.fx = cam.fy = 1400.0 + 20.0 * c;
    cam.cx = 960.0 + 3.0 * c;
    cam.cy = 540.0 - 2.0 * c;
    cam.distortion = {-0.12, 0.05, 0.0005, -0.0003, 0.0};
    const double a = 2.0 * M_PI * c / cameras;
    const Eigen::Vector3d center(4.5 * std::cos(a), 4.5 * std::sin(a), 1.5 + 0.1 * c);
    const Eigen::Vector3d target(0, 0, 1.0);
    const Eigen::Vector3d z = (target - center).normalized();                  // forward
    const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();  // right
    const Eigen::Vector3d y = z.cross(x);                                      // down
    Eigen::Matrix3d r_cw;
    r_cw.row(0) = x;
    r_cw.row(1) = y;
    r_cw.row(2) = z;
    cam.rotation = r_cw;
    cam.translation = -r_cw * center;
    s.rig.cameras.push_back(cam);
  }
  return s;
}

Eigen::VectorXd RandomPose(const Skeleton& skeleton, std::mt19937* rng, double max_angle) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd theta(skeleton.pose_dim());
  for (int i = 0; i < theta.size(); ++i) theta(i) = max_angle * u(*rng);
  theta.head<3>() = Eigen::Vector3d(0.3 * u(*rng), 0.3 * u(*rng), 0.95 + 0.05 * u(*rng));
  theta.segment<3>(3) = Eigen::Vector3d(0.1 * u(*rng), 0.1 * u(*rng), M_PI * u(*rng));
  return theta;
}

Eigen::VectorXd Perturb(const Eigen::VectorXd& theta, double angle, double shift,
                        std::mt19937* rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::VectorXd out = theta;
  out.head<3>() += shift * Eigen::Vector3d(n(*rng), n(*rng), n(*rng)).normalized();
  for (int i = 3; i < theta.size(); i += 3) {
    const Eigen::Vector3d axis = Eigen::Vector3d(n(*rng), n(*rng), n(*rng)).normalized();
    out.segment<3>(i) = Log(Exp(theta.segment<3>(i)) * Exp(angle * axis));
  }
  return out;
}

namespace {
Eigen::Vector3d ImuSiteWorld(const BodyPose& pose, const ImuSite& s) {
  return pose.position[s.bone] + pose.rotation[s.bone] * s.offset;
}
}  // namespace

FrameObservations Render(const Scene& scene, const Eigen::VectorXd& theta, double timestamp) {
  BodyPose pose;
  ForwardKinematics(scene.skeleton, theta.data(), &pose);
  FrameObservations f;
  f.timestamp = timestamp;
  for (int c = 0; c < static_cast<int>(scene.rig.cameras.size()); ++c) {
    CameraObservation obs;
    obs.camera = c;
    for (const Site& site : scene.layout.sites) {
      Eigen::Vector2d px;
      Keypoint2D kp;
      if (scene.rig.cameras[c].Project(
              pose.position[site.bone] + pose.rotation[site.bone] * site.offset, &px)) {
        kp = {px.x(), px.y(), 1.0};
      }
      obs.keypoints.push_back(kp);
    }
    f.cameras.push_back(obs);
  }
  for (int i = 0; i < static_cast<int>(scene.imus.size()); ++i) {
    const ImuSite& s = scene.imus[i];
    ImuObservation obs;
    obs.imu = i;
    // R_i = R_ig^T * G_b * R_m
    obs.orientation = Eigen::Quaterniond(s.reference.transpose() * pose.rotation[s.bone] * s.mount);
    obs.has_acceleration = false;  // see SetAccelerations
    f.imus.push_back(obs);
  }
  return f;
}

void SetAccelerations(const Scene& scene, const Eigen::VectorXd& theta0, double t0,
                      const Eigen::VectorXd& theta1, double t1, const Eigen::VectorXd& theta2,
                      double t2, const Eigen::Vector3d& accel_at_rest, FrameObservations* frame1) {
  BodyPose p0, p1, p2;
  ForwardKinematics(scene.skeleton, theta0.data(), &p0);
  ForwardKinematics(scene.skeleton, theta1.data(), &p1);
  ForwardKinematics(scene.skeleton, theta2.data(), &p2);
  const double h1 = t1 - t0, h2 = t2 - t1;
  for (ImuObservation& obs : frame1->imus) {
    const ImuSite& s = scene.imus[obs.imu];
    const Eigen::Vector3d x0 = ImuSiteWorld(p0, s), x1 = ImuSiteWorld(p1, s),
                          x2 = ImuSiteWorld(p2, s);
    const Eigen::Vector3d a_world = 2.0 * ((x2 - x1) / h2 - (x1 - x0) / h1) / (h1 + h2);
    // a = R_ig R_i a_i - a_g  =>  a_i = (R_ig R_i)^T (a + a_g)
    const Eigen::Matrix3d sensor_world = p1.rotation[s.bone] * s.mount;
    obs.acceleration = sensor_world.transpose() * (a_world + accel_at_rest);
    obs.has_acceleration = true;
  }
}

double MaxJointError(const Skeleton& skeleton, const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  BodyPose pa, pb;
  ForwardKinematics(skeleton, a.data(), &pa);
  ForwardKinematics(skeleton, b.data(), &pb);
  double worst = 0.0;
  for (int i = 0; i < skeleton.num_bones(); ++i) {
    worst = std::max(worst, (pa.position[i] - pb.position[i]).norm());
  }
  return worst;
}

double MaxBoneAngleError(const Skeleton& skeleton, const Eigen::VectorXd& a,
                         const Eigen::VectorXd& b) {
  BodyPose pa, pb;
  ForwardKinematics(skeleton, a.data(), &pa);
  ForwardKinematics(skeleton, b.data(), &pb);
  double worst = 0.0;
  for (int i = 0; i < skeleton.num_bones(); ++i) {
    worst = std::max(worst, AngleBetween(pa.rotation[i], pb.rotation[i]));
  }
  return worst;
}

double MaxSiteError(const Scene& scene, const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  BodyPose pa, pb;
  ForwardKinematics(scene.skeleton, a.data(), &pa);
  ForwardKinematics(scene.skeleton, b.data(), &pb);
  double worst = 0.0;
  for (const Site& s : scene.layout.sites) {
    const Eigen::Vector3d xa = pa.position[s.bone] + pa.rotation[s.bone] * s.offset;
    const Eigen::Vector3d xb = pb.position[s.bone] + pb.rotation[s.bone] * s.offset;
    worst = std::max(worst, (xa - xb).norm());
  }
  return worst;
}

PosePrior PriorThrough(const std::vector<Eigen::VectorXd>& poses, int rank, std::mt19937* rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  const int dof = static_cast<int>(poses.back().size()) - 6;
  const Eigen::VectorXd mean = poses.back().tail(dof);
  const int spanned = static_cast<int>(poses.size()) - 1;
  if (spanned >= rank) throw std::invalid_argument("PriorThrough: more poses than the rank spans");
  Eigen::MatrixXd g(dof, rank);
  for (int i = 0; i < g.size(); ++i) g(i) = n(*rng);
  for (int c = 0; c < spanned; ++c) g.col(c) = poses[c].tail(dof) - mean;
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(g);
  PosePrior p;
  p.basis = Eigen::MatrixXd(qr.householderQ()).leftCols(rank);
  p.mean = mean;
  p.sigma = Eigen::VectorXd::LinSpaced(rank, 0.5, 0.1);
  p.sigma.head(spanned).setConstant(1e3);
  return p;
}

PosePrior RandomPrior(int dof, int rank, const Eigen::VectorXd& theta_mean, std::mt19937* rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::MatrixXd g(dof, rank);
  for (int i = 0; i < g.size(); ++i) g(i) = n(*rng);
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(g);
  PosePrior p;
  p.basis = Eigen::MatrixXd(qr.householderQ()).leftCols(rank);
  p.mean = theta_mean.tail(dof);
  p.sigma = Eigen::VectorXd::LinSpaced(rank, 0.5, 0.1);
  return p;
}

SolverOptions ExactOptions() {
  SolverOptions o;
  o.max_iterations = 50;
  o.function_tolerance = 1e-14;
  o.gradient_tolerance = 1e-14;
  o.parameter_tolerance = 1e-12;
  o.motion.enabled = false;  // E_M smooths: mm off noise-free frames of an accelerating motion
  return o;
}

std::unique_ptr<Solver> MakeSolver(const Scene& scene, std::optional<PosePrior> prior,
                                   SolverOptions options) {
  std::string error;
  auto solver =
      Solver::Create(scene.skeleton, scene.rig, scene.layout, scene.imus, prior, options, &error);
  EXPECT_NE(solver, nullptr) << error;
  return solver;
}

}  // namespace mocap::testing
