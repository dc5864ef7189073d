// A solved frame as PoseFrame: the pose, each bone's world transform by forward kinematics,
// the solve's figures, and the names of what it was solved with.
#include "pose_frame_encoder.h"

#include <gtest/gtest.h>

#include "synthetic_scene.h"

namespace mocap {
namespace {

TEST(PoseFrameEncoder, APoseFrameCarriesThePoseItsJointsAndWhatItWasSolvedWith) {
  const testing::Scene scene = testing::MakeScene(3);
  std::mt19937 rng(4);
  SolveResult r;
  r.status = SolveStatus::kInitialised;
  r.theta = testing::RandomPose(scene.skeleton, &rng);
  r.costs.position = 1.5, r.costs.pca_deviation = 0.25, r.costs.ground = 0.125;
  r.iterations = 7, r.solve_time_ms = 2.5, r.flags = kIterationLimit | kReinitialised;
  FrameObservations frame;
  frame.cameras.resize(2), frame.cameras[0].camera = 2, frame.cameras[1].camera = 0;
  frame.imus.resize(2), frame.imus[0].imu = 3, frame.imus[1].imu = 5;
  r.imus_distrusted = {5};  // given, but left out of the solve
  const v1::PoseFrame p = EncodePoseFrame(frame, r, 1234, 9, scene.skeleton, scene.rig, scene.imus);
  EXPECT_EQ(p.capture_time_ns(), 1234);
  EXPECT_EQ(p.frame_index(), 9u);
  EXPECT_EQ(p.status(), v1::PoseFrame::STATUS_INITIALISED);
  ASSERT_EQ(p.theta_size(), r.theta.size());
  EXPECT_EQ(p.theta(10), r.theta(10));
  BodyPose pose;
  ForwardKinematics(scene.skeleton, r.theta.data(), &pose);
  ASSERT_EQ(p.joints_size(), scene.skeleton.num_bones());
  const int b = scene.skeleton.BoneIndex("hand_l");
  const v1::JointTransform& j = p.joints(b);
  EXPECT_EQ(j.name(), "hand_l");
  EXPECT_NEAR((Eigen::Vector3d(j.px(), j.py(), j.pz()) - pose.position[b]).norm(), 0, 1e-12);
  const Eigen::Quaterniond q(j.qw(), j.qx(), j.qy(), j.qz());  // w, x, y, z on the wire
  EXPECT_NEAR((q.toRotationMatrix() - pose.rotation[b]).norm(), 0, 1e-12);
  EXPECT_EQ(p.costs().position(), 1.5);
  EXPECT_EQ(p.costs().pca_deviation(), 0.25);
  EXPECT_EQ(p.costs().ground(), 0.125);
  EXPECT_EQ(p.iterations(), 7);
  EXPECT_EQ(p.solve_time_ms(), 2.5);
  EXPECT_EQ(p.quality_flags(), static_cast<uint32_t>(v1::PoseFrame::QUALITY_ITERATION_LIMIT |
                                                     v1::PoseFrame::QUALITY_REINITIALISED));
  ASSERT_EQ(p.cameras_size(), 2);
  EXPECT_EQ(p.cameras(0), scene.rig.cameras[2].name);
  EXPECT_EQ(p.cameras(1), scene.rig.cameras[0].name);
  ASSERT_EQ(p.imus_size(), 1);
  EXPECT_EQ(p.imus(0), scene.imus[3].name);
  ASSERT_EQ(p.imus_distrusted_size(), 1);
  EXPECT_EQ(p.imus_distrusted(0), scene.imus[5].name);
}

TEST(PoseFrameEncoder, EveryStatusHasItsOwnValue) {
  EXPECT_EQ(ToProto(SolveStatus::kOk), v1::PoseFrame::STATUS_OK);
  EXPECT_EQ(ToProto(SolveStatus::kInitialised), v1::PoseFrame::STATUS_INITIALISED);
  EXPECT_EQ(ToProto(SolveStatus::kNoObservations), v1::PoseFrame::STATUS_NO_OBSERVATIONS);
  EXPECT_EQ(ToProto(SolveStatus::kRejectedFrame), v1::PoseFrame::STATUS_REJECTED_FRAME);
  EXPECT_EQ(ToProto(SolveStatus::kFailed), v1::PoseFrame::STATUS_FAILED);
}

}  // namespace
}  // namespace mocap
