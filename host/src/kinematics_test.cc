#include "mocap/kinematics.h"

#include <gtest/gtest.h>

#include <random>

#include "mocap/so3.h"
#include "synthetic_scene.h"

namespace mocap {
namespace {

constexpr double kTol = 1e-12;

// pelvis -> spine (0,0,0.5) -> arm (0,0.4,0)
Skeleton ThreeBones() {
  Skeleton s;
  std::string error;
  EXPECT_TRUE(Skeleton::Create(
      {{"pelvis", -1, {0, 0, 0}}, {"spine", 0, {0, 0, 0.5}}, {"arm", 1, {0, 0.4, 0}}}, &s, &error))
      << error;
  return s;
}

TEST(ForwardKinematics, RestPoseIsTheSumOfOffsets) {
  const Skeleton s = ThreeBones();
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(s.pose_dim());
  theta.head<3>() << 1, 2, 3;
  BodyPose pose;
  ForwardKinematics(s, theta.data(), &pose);
  EXPECT_LT((pose.position[2] - Eigen::Vector3d(1, 2.4, 3.5)).norm(), kTol);
  EXPECT_LT((pose.rotation[2] - Eigen::Matrix3d::Identity()).norm(), kTol);
}

TEST(ForwardKinematics, HandComputedPose) {
  // Root yaw +90 deg about z; spine bends +90 deg about x.
  // spine origin: R_z(90) * (0,0,0.5) = (0,0,0.5)
  // arm origin: spine + R_z(90) R_x(90) * (0,0.4,0) = (0,0,0.5) + R_z(90)*(0,0,0.4) = (0,0,0.9)
  // arm orientation: R_z(90) R_x(90)
  const Skeleton s = ThreeBones();
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(s.pose_dim());
  theta.segment<3>(3) << 0, 0, M_PI / 2;
  theta.segment<3>(6) << M_PI / 2, 0, 0;
  BodyPose pose;
  ForwardKinematics(s, theta.data(), &pose);
  EXPECT_LT((pose.position[1] - Eigen::Vector3d(0, 0, 0.5)).norm(), 1e-12);
  EXPECT_LT((pose.position[2] - Eigen::Vector3d(0, 0, 0.9)).norm(), 1e-12);
  Eigen::Matrix3d expected;
  // R_z(90) = [0 -1 0; 1 0 0; 0 0 1], R_x(90) = [1 0 0; 0 0 -1; 0 1 0]
  expected << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  EXPECT_LT((pose.rotation[2] - expected).norm(), 1e-12);
  // A point 0.1 along the arm's own y axis sits at +z in world after the bend.
  EXPECT_LT((pose.rotation[2] * Eigen::Vector3d(0, 0.1, 0) - Eigen::Vector3d(0, 0, 0.1)).norm(),
            1e-12);
}

TEST(ForwardKinematics, PointAndRotationJacobiansMatchFiniteDifferences) {
  const testing::Scene scene = testing::MakeScene(1);
  const Skeleton& s = scene.skeleton;
  std::mt19937 rng(7);
  const Eigen::VectorXd theta = testing::RandomPose(s, &rng);
  BodyPose pose;
  ForwardKinematics(s, theta.data(), &pose);
  const int hand = s.BoneIndex("hand_l");
  const Eigen::Vector3d offset(0.03, 0.08, -0.01);
  const Eigen::Vector3d x = pose.position[hand] + pose.rotation[hand] * offset;
  // Chain-block Jacobians scattered into full pose-vector columns.
  Eigen::MatrixXd jp = Eigen::MatrixXd::Zero(3, s.pose_dim()), jr = jp;
  const std::vector<int>& chain = s.Chain(hand);
  std::vector<std::vector<double>> bp(chain.size()), br(chain.size());
  std::vector<double*> ptr_p, ptr_r;
  for (size_t i = 0; i < chain.size(); ++i) {
    bp[i].assign(3 * BlockSize(chain[i]), 0.0);
    br[i].assign(3 * BlockSize(chain[i]), 0.0);
    ptr_p.push_back(bp[i].data());
    ptr_r.push_back(br[i].data());
  }
  PointJacobian<3>(s, pose, hand, x, Eigen::Matrix3d::Identity(), ptr_p.data());
  RotationJacobian<3>(s, pose, hand, Eigen::Matrix3d::Identity(), ptr_r.data());
  for (size_t i = 0; i < chain.size(); ++i) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < BlockSize(chain[i]); ++c) {
        jp(r, BlockOffset(chain[i]) + c) = bp[i][r * BlockSize(chain[i]) + c];
        jr(r, BlockOffset(chain[i]) + c) = br[i][r * BlockSize(chain[i]) + c];
      }
    }
  }
  const double h = 1e-7;
  for (int k = 0; k < s.pose_dim(); ++k) {
    Eigen::VectorXd t2 = theta;
    t2(k) += h;
    BodyPose p2;
    ForwardKinematics(s, t2.data(), &p2);
    const Eigen::Vector3d dx = (p2.position[hand] + p2.rotation[hand] * offset - x) / h;
    const Eigen::Vector3d dphi = Log(p2.rotation[hand] * pose.rotation[hand].transpose()) / h;
    for (int r = 0; r < 3; ++r) {
      EXPECT_NEAR(jp(r, k), dx(r), 1e-5) << "point, column " << k;
      EXPECT_NEAR(jr(r, k), dphi(r), 1e-5) << "rotation, column " << k;
    }
  }
}

TEST(KinematicsCache, FollowsChangesOfAnyBlockOnTheChain) {
  const Skeleton s = ThreeBones();
  KinematicsCache cache(&s);
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(s.pose_dim());
  auto arm = [&] { return cache.Update(2, ChainBlocks(s, 2, theta.data()).data()).position[2]; };
  EXPECT_NEAR(arm().y(), 0.4, kTol);
  theta(0) = 1.0;  // root translation
  EXPECT_NEAR(arm().x(), 1.0, kTol);
  theta.segment<3>(6) << M_PI / 2, 0, 0;  // spine bend: the arm's origin moves with its parent
  EXPECT_LT((arm() - Eigen::Vector3d(1.0, 0, 0.9)).norm(), kTol);
  // The same values in another buffer (as Ceres' candidate points are) give the same pose.
  Eigen::VectorXd copy = theta;
  EXPECT_LT((cache.Update(2, ChainBlocks(s, 2, copy.data()).data()).position[2] -
             Eigen::Vector3d(1.0, 0, 0.9))
                .norm(),
            kTol);
}

TEST(Skeleton, RejectsMalformedTrees) {
  Skeleton s;
  std::string error;
  EXPECT_FALSE(Skeleton::Create({}, &s, &error));
  EXPECT_FALSE(Skeleton::Create({{"a", -1, {0, 0, 0}}, {"b", 2, {0, 0, 0}}, {"c", 0, {0, 0, 0}}},
                                &s, &error));
  EXPECT_FALSE(Skeleton::Create({{"a", -1, {0, 0, 0}}, {"a", 0, {0, 0, 0}}}, &s, &error));
  EXPECT_FALSE(Skeleton::Create({{"a", -1, {0, 0, 0}}, {"b", -1, {0, 0, 0}}}, &s, &error));
  EXPECT_FALSE(Skeleton::Create({{"a", -1, {0, NAN, 0}}}, &s, &error));
  EXPECT_FALSE(error.empty());
}

}  // namespace
}  // namespace mocap
