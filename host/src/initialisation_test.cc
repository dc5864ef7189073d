#include "mocap/initialisation.h"

#include <gtest/gtest.h>

#include <random>

#include "mocap/so3.h"
#include "synthetic_scene.h"

namespace mocap {
namespace {

// A pose whose torso (pelvis, spine, clavicles) is at rest relative to the root, so the
// torso keypoints are a rigid copy of the rest pose's.
Eigen::VectorXd RigidTorsoPose(const Skeleton& s, std::mt19937* rng) {
  Eigen::VectorXd theta = testing::RandomPose(s, rng, 0.4);
  for (const char* bone : {"spine_lower", "spine_upper", "clavicle_l", "clavicle_r"}) {
    theta.segment<3>(Skeleton::RotationIndex(s.BoneIndex(bone))).setZero();
  }
  return theta;
}

std::vector<Detection> Detections(const testing::Scene& scene, const FrameObservations& f) {
  std::vector<Detection> out;
  for (const CameraObservation& c : f.cameras) {
    for (int k = 0; k < static_cast<int>(c.keypoints.size()); ++k) {
      if (c.keypoints[k].confidence > 0)
        out.push_back({c.camera, k, {c.keypoints[k].x, c.keypoints[k].y}, 1.0});
    }
  }
  return out;
}

std::vector<std::optional<Eigen::Matrix3d>> ImuWorld(const testing::Scene& scene,
                                                     const FrameObservations& f) {
  std::vector<std::optional<Eigen::Matrix3d>> out(scene.imus.size());
  for (const ImuObservation& o : f.imus)
    out[o.imu] = scene.imus[o.imu].reference * o.orientation.toRotationMatrix();
  return out;
}

TEST(Initialisation, TriangulatesExactly) {
  const testing::Scene scene = testing::MakeScene(3);
  const Eigen::Vector3d x(0.3, -0.2, 1.4);
  std::vector<Detection> views;
  for (int c = 0; c < 3; ++c) {
    Eigen::Vector2d px;
    ASSERT_TRUE(scene.rig.cameras[c].Project(x, &px));
    views.push_back({c, 0, px, 1.0});
  }
  Eigen::Vector3d y;
  ASSERT_TRUE(TriangulatePoint(scene.rig, views, &y));
  EXPECT_LT((x - y).norm(), 1e-9);
  views.resize(1);
  EXPECT_FALSE(TriangulatePoint(scene.rig, views, &y));
}

TEST(Initialisation, RootFromTriangulatedTorsoWithoutImus) {
  const testing::Scene scene = testing::MakeScene(4);
  std::mt19937 rng(3);
  const Eigen::VectorXd truth = RigidTorsoPose(scene.skeleton, &rng);
  const FrameObservations f = testing::Render(scene, truth, 0.0);
  const InitialPose init =
      EstimateInitialPose(scene.skeleton, scene.rig, scene.layout, scene.imus, Detections(scene, f),
                          std::vector<std::optional<Eigen::Matrix3d>>(13));
  ASSERT_TRUE(init.position_known);
  EXPECT_LT((init.theta.head<3>() - truth.head<3>()).norm(), 1e-6);
  EXPECT_LT(AngleBetween(Exp(init.theta.segment<3>(3)), Exp(truth.segment<3>(3))), 1e-6);
}

TEST(Initialisation, DepthFromOneView) {
  const testing::Scene scene = testing::MakeScene(1);
  std::mt19937 rng(4);
  Eigen::VectorXd truth = RigidTorsoPose(scene.skeleton, &rng);
  truth.segment(6, 60) *= 0.2;  // nearly the rest pose: the spread is the rest pose's
  const FrameObservations f = testing::Render(scene, truth, 0.0);
  const InitialPose init =
      EstimateInitialPose(scene.skeleton, scene.rig, scene.layout, scene.imus, Detections(scene, f),
                          std::vector<std::optional<Eigen::Matrix3d>>(13));
  ASSERT_TRUE(init.position_known);
  const Camera& cam = scene.rig.cameras[0];
  const double true_depth = (cam.rotation * truth.head<3>() + cam.translation).z();
  const double depth = (cam.rotation * init.theta.head<3>() + cam.translation).z();
  EXPECT_NEAR(depth, true_depth, 0.15 * true_depth);
}

TEST(Initialisation, BoneOrientationsFromImusAlone) {
  const testing::Scene scene = testing::MakeScene(0);
  std::mt19937 rng(5);
  const Eigen::VectorXd truth = testing::RandomPose(scene.skeleton, &rng);
  const FrameObservations f = testing::Render(scene, truth, 0.0);
  const InitialPose init = EstimateInitialPose(scene.skeleton, scene.rig, scene.layout, scene.imus,
                                               {}, ImuWorld(scene, f));
  EXPECT_FALSE(init.position_known);
  BodyPose a, b;
  ForwardKinematics(scene.skeleton, init.theta.data(), &a);
  ForwardKinematics(scene.skeleton, truth.data(), &b);
  for (const ImuSite& s : scene.imus) {
    EXPECT_LT(AngleBetween(a.rotation[s.bone], b.rotation[s.bone]), 1e-9) << s.name;
  }
}

}  // namespace
}  // namespace mocap
