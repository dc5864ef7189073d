// Ground contact (ground.h): the feet's contact sites lie on the sole line, and the floor is
// where the lowest of them usually is, whatever a jump or a skeleton without feet does.
#include "mocap/ground.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "synthetic_scene.h"

namespace mocap {
namespace {

Eigen::Vector3d World(const BodyPose& pose, const Site& s) {
  return pose.position[s.bone] + pose.rotation[s.bone] * s.offset;
}

TEST(Ground, ContactSitesAreHeelBallAndToeOnEachSole) {
  const Skeleton skeleton = testing::MakeScene(1).skeleton;
  const std::vector<Site> sites = FootContactSites(skeleton);
  ASSERT_EQ(sites.size(), 6u);
  BodyPose rest;
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(skeleton.pose_dim());
  ForwardKinematics(skeleton, zero.data(), &rest);
  for (const char* side : {"_l", "_r"}) {
    const int foot = skeleton.BoneIndex(std::string("foot") + side);
    const int toes = skeleton.BoneIndex(std::string("toes") + side);
    const int first = side[1] == 'l' ? 0 : 3;
    const Eigen::Vector3d heel = World(rest, sites[first]), ball = World(rest, sites[first + 1]),
                          toe = World(rest, sites[first + 2]);
    EXPECT_EQ(sites[first].bone, foot);
    EXPECT_EQ(sites[first + 1].bone, toes);
    EXPECT_EQ(sites[first + 2].bone, toes);
    EXPECT_LT((ball - rest.position[toes]).norm(), 1e-12);  // the ball is the toes' joint
    // One sole line at the ball's height, heel behind the ankle, toe tip ahead of the ball
    // (the rest pose faces +x).
    EXPECT_NEAR(heel.z(), ball.z(), 1e-12);
    EXPECT_NEAR(toe.z(), ball.z(), 1e-12);
    EXPECT_LT(heel.x(), rest.position[foot].x() - 0.03);
    EXPECT_GT(toe.x(), ball.x() + 0.04);
    EXPECT_NEAR(heel.y(), rest.position[foot].y(), 1e-12);
  }
  // A foot without toes has no sites.
  std::vector<Skeleton::Bone> bones = skeleton.bones();
  bones.resize(skeleton.BoneIndex("toes_l"));  // pelvis ... foot_l
  Skeleton no_toes;
  std::string error;
  ASSERT_TRUE(Skeleton::Create(bones, &no_toes, &error)) << error;
  EXPECT_TRUE(FootContactSites(no_toes).empty());
}

TEST(Ground, TheFloorIsWhereTheLowestContactUsuallyIsAJumpAside) {
  const Skeleton skeleton = testing::MakeScene(1).skeleton;
  const std::vector<Site> sites = FootContactSites(skeleton);
  std::mt19937 rng(3);
  std::vector<Eigen::VectorXd> poses;
  std::vector<double> lowest;
  BodyPose pose;
  for (int f = 0; f < 31; ++f) {
    Eigen::VectorXd theta = testing::RandomPose(skeleton, &rng, 0.3);
    ForwardKinematics(skeleton, theta.data(), &pose);
    double z = 1e9;
    for (const Site& s : sites) z = std::min(z, World(pose, s).z());
    theta[2] += 0.02 - z;                        // the lowest site 2 cm above z = 0 ...
    if (f % 3 == 0) theta[2] += 0.3 + 0.01 * f;  // ... but in a third of them, in the air
    poses.push_back(theta);
  }
  EXPECT_NEAR(FloorHeight(skeleton, poses), 0.02, 1e-12);
  poses.push_back(Eigen::VectorXd::Constant(skeleton.pose_dim(), NAN));  // skipped
  EXPECT_NEAR(FloorHeight(skeleton, poses), 0.02, 1e-12);
  // Unknown: no poses, a pose of another skeleton's size, no feet.
  EXPECT_TRUE(std::isnan(FloorHeight(skeleton, {})));
  EXPECT_TRUE(std::isnan(FloorHeight(skeleton, {Eigen::VectorXd::Zero(12)})));
  Skeleton trunk;
  std::string error;
  ASSERT_TRUE(Skeleton::Create({skeleton.bone(0), skeleton.bone(1)}, &trunk, &error)) << error;
  EXPECT_TRUE(std::isnan(FloorHeight(trunk, {Eigen::VectorXd::Zero(trunk.pose_dim())})));
}

}  // namespace
}  // namespace mocap
