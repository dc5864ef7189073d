// Each residual: analytic Jacobian against numeric differentiation (ceres::GradientChecker),
// zero at the true pose, and growing as the pose moves away from it.
#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include <functional>
#include <memory>
#include <random>

#include "mocap/ground.h"
#include "mocap/residuals/acceleration_residual.h"
#include "mocap/residuals/calibration_residuals.h"
#include "mocap/residuals/ground_residual.h"
#include "mocap/residuals/motion_residual.h"
#include "mocap/residuals/orientation_residual.h"
#include "mocap/residuals/pca_prior_residuals.h"
#include "mocap/residuals/point_residual.h"
#include "mocap/residuals/position_residual.h"
#include "mocap/so3.h"
#include "mocap/solver.h"
#include "synthetic_scene.h"

namespace mocap {
namespace {

constexpr double kJacobianRelativePrecision = 1e-5;
constexpr double kZeroAtTruth = 1e-9;

// The parameter blocks a residual takes, as pointers into a pose vector.
using BlocksOf = std::function<std::vector<double*>(Eigen::VectorXd*)>;

BlocksOf ChainOf(const Skeleton& s, int bone) {
  return [&s, bone](Eigen::VectorXd* theta) { return ChainBlocks(s, bone, theta->data()); };
}

BlocksOf JointsOf(const Skeleton& s) {
  return [&s](Eigen::VectorXd* theta) {
    std::vector<double*> blocks;
    for (int b = 1; b < s.num_bones(); ++b) blocks.push_back(theta->data() + BlockOffset(b));
    return blocks;
  };
}

double SquaredNorm(const ceres::CostFunction& f, const BlocksOf& blocks, Eigen::VectorXd theta) {
  Eigen::VectorXd r(f.num_residuals());
  EXPECT_TRUE(f.Evaluate(blocks(&theta).data(), r.data(), nullptr));
  return r.squaredNorm();
}

void ExpectJacobianCorrect(const ceres::CostFunction& f, const BlocksOf& blocks,
                           Eigen::VectorXd theta) {
  ceres::NumericDiffOptions numeric;
  const std::vector<const ceres::Manifold*>* no_manifolds = nullptr;
  ceres::GradientChecker checker(&f, no_manifolds, numeric);
  ceres::GradientChecker::ProbeResults results;
  EXPECT_TRUE(checker.Probe(blocks(&theta).data(), kJacobianRelativePrecision, &results))
      << results.error_log;
}

// Zero at theta_true, and strictly growing along a fixed perturbation direction.
void ExpectZeroAtTruthAndGrowing(const ceres::CostFunction& f, const BlocksOf& blocks,
                                 const Eigen::VectorXd& theta_true, std::mt19937* rng) {
  EXPECT_LT(SquaredNorm(f, blocks, theta_true), kZeroAtTruth);
  double previous = 0.0;
  for (double deg : {1.0, 3.0, 10.0}) {
    std::mt19937 same = *rng;  // same axes at every magnitude
    const Eigen::VectorXd away =
        testing::Perturb(theta_true, deg * M_PI / 180.0, 0.01 * deg, &same);
    const double e = SquaredNorm(f, blocks, away);
    EXPECT_GT(e, previous) << deg << " degrees";
    previous = e;
  }
}

class ResidualsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    scene_ = testing::MakeScene(2);
    truth_ = testing::RandomPose(scene_.skeleton, &rng_);
    fk_ = std::make_unique<KinematicsCache>(&scene_.skeleton);
    ForwardKinematics(scene_.skeleton, truth_.data(), &pose_);
  }
  std::mt19937 rng_{42};
  testing::Scene scene_;
  Eigen::VectorXd truth_;
  BodyPose pose_;
  std::unique_ptr<KinematicsCache> fk_;
};

TEST_F(ResidualsTest, Orientation) {
  for (const ImuSite& site : scene_.imus) {
    const Eigen::Matrix3d measured = pose_.rotation[site.bone] * site.mount;
    OrientationResidual f(fk_.get(), site, measured, 100.0);
    ExpectJacobianCorrect(f, ChainOf(scene_.skeleton, site.bone),
                          testing::Perturb(truth_, 0.2, 0.1, &rng_));
    ExpectZeroAtTruthAndGrowing(f, ChainOf(scene_.skeleton, site.bone), truth_, &rng_);
  }
}

// Parameter blocks of a calibration residual: a copy of theta's chain, then extra blocks.
struct CalibrationBlocks {
  Eigen::VectorXd theta;
  std::vector<std::vector<double>> extra;
  std::vector<double*> Pointers(const Skeleton& s, int bone) {
    std::vector<double*> p = ChainBlocks(s, bone, theta.data());
    for (auto& e : extra) p.push_back(e.data());
    return p;
  }
};

void ExpectAllJacobiansCorrect(const ceres::CostFunction& f, std::vector<double*> blocks) {
  ceres::NumericDiffOptions numeric;
  const std::vector<const ceres::Manifold*>* no_manifolds = nullptr;
  ceres::GradientChecker checker(&f, no_manifolds, numeric);
  ceres::GradientChecker::ProbeResults results;
  EXPECT_TRUE(checker.Probe(blocks.data(), kJacobianRelativePrecision, &results))
      << results.error_log;
}

TEST_F(ResidualsTest, SiteReprojectionWithScalesAndSiteAsParameters) {
  // Length groups: each limb pair and the trunk; the site and the scales move the point.
  std::vector<int> group(scene_.skeleton.num_bones(), -1), shift(group);
  for (int b = 1; b < scene_.skeleton.num_bones(); ++b) group[b] = b % 4;
  for (const char* name : {"thigh_l", "thigh_r", "clavicle_l", "clavicle_r", "neck"})
    shift[scene_.skeleton.BoneIndex(name)] = std::string(name) == "neck" ? 1 : 0;
  const Camera& cam = scene_.rig.cameras[0];
  int checked = 0;
  for (const Site& site : scene_.layout.sites) {
    Eigen::Vector2d px;
    if (!cam.Project(pose_.position[site.bone] + pose_.rotation[site.bone] * site.offset, &px))
      continue;
    ScaledChain chain(&scene_.skeleton, site.bone, group, shift);
    SiteReprojectionResidual f(chain, &cam, px, 0.8, 0.04);
    CalibrationBlocks at{truth_, {{site.offset.x(), site.offset.y(), site.offset.z()}}};
    for (int u = 0; u < chain.num_scale_blocks(); ++u) at.extra.push_back({1.0});
    for (int v = 0; v < chain.num_shift_blocks(); ++v) at.extra.push_back({0.0, 0.0, 0.0});
    Eigen::Vector2d r;
    ASSERT_TRUE(f.Evaluate(at.Pointers(scene_.skeleton, site.bone).data(), r.data(), nullptr));
    EXPECT_LT(r.norm(), 1e-9);  // zero at the truth with unit scales
    CalibrationBlocks away{testing::Perturb(truth_, 0.1, 0.05, &rng_), at.extra};
    away.extra[0][1] += 0.02;
    for (size_t u = 1; u < away.extra.size(); ++u) {
      for (double& v : away.extra[u]) v += 0.05 * u;
    }
    ExpectAllJacobiansCorrect(f, away.Pointers(scene_.skeleton, site.bone));
    ++checked;
  }
  EXPECT_GT(checked, 20);
  // A scale of 1.1 on every group moves a hand keypoint as a 10% longer skeleton does.
  std::vector<Skeleton::Bone> bones = scene_.skeleton.bones();
  for (size_t b = 1; b < bones.size(); ++b) bones[b].offset *= 1.1;
  Skeleton longer;
  std::string error;
  ASSERT_TRUE(Skeleton::Create(bones, &longer, &error)) << error;
  const std::vector<int> one_group(scene_.skeleton.num_bones(), 0);
  const int hand = scene_.skeleton.BoneIndex("hand_l");
  BodyPose expected;
  ForwardKinematics(longer, truth_.data(), &expected);
  Eigen::Vector2d px;
  ASSERT_TRUE(cam.Project(expected.position[hand], &px));
  SiteReprojectionResidual f(ScaledChain(&scene_.skeleton, hand, one_group), &cam, px, 1.0, 1.0);
  CalibrationBlocks at{truth_, {{0.0, 0.0, 0.0}, {1.1}}};
  Eigen::Vector2d r;
  ASSERT_TRUE(f.Evaluate(at.Pointers(scene_.skeleton, hand).data(), r.data(), nullptr));
  EXPECT_LT(r.norm(), 1e-9);
}

TEST_F(ResidualsTest, ShiftGroupsMoveLeftAndRightMirrored) {
  // One shift group for both hips: a shift of (0.01, 0.02, 0.03) moves the left hip by it and
  // the right hip by (0.01, -0.02, 0.03), in the pelvis frame.
  std::vector<int> shift(scene_.skeleton.num_bones(), -1);
  const int left = scene_.skeleton.BoneIndex("thigh_l"),
            right = scene_.skeleton.BoneIndex("thigh_r");
  shift[left] = shift[right] = 0;
  const Eigen::Vector3d d(0.01, 0.02, 0.03);
  for (const auto& [bone, moved] :
       {std::pair{left, d}, std::pair{right, Eigen::Vector3d(0.01, -0.02, 0.03)}}) {
    ScaledChain chain(&scene_.skeleton, bone, {}, shift);
    ASSERT_EQ(chain.num_shift_blocks(), 1);
    std::vector<double*> blocks = ChainBlocks(scene_.skeleton, bone, truth_.data());
    const double* shifts[1] = {d.data()};
    BodyPose pose;
    chain.Pose(blocks.data(), nullptr, shifts, &pose);
    const Eigen::Vector3d expected = pose_.position[bone] + pose_.rotation[0] * moved;
    EXPECT_LT((pose.position[bone] - expected).norm(), 1e-12);
  }
}

TEST_F(ResidualsTest, MountedOrientationWithMountingAndHeadingAsParameters) {
  for (const ImuSite& site : scene_.imus) {
    // Measured in a reference frame turned by 0.7 rad about z: the heading 0.7 undoes it.
    const Eigen::Matrix3d measured =
        Exp(Eigen::Vector3d(0, 0, -0.7)) * pose_.rotation[site.bone] * site.mount;
    const Eigen::Matrix3d mount0 = site.mount * Exp(Eigen::Vector3d(0.1, -0.2, 0.05));
    MountedOrientationResidual f(ScaledChain(&scene_.skeleton, site.bone, {}), mount0, measured,
                                 100.0);
    // The true mounting is mount0 Exp(m) with m = Log(mount0^T mount).
    const Eigen::Vector3d m = Log(mount0.transpose() * site.mount);
    CalibrationBlocks at{truth_, {{m.x(), m.y(), m.z()}, {0.7}}};
    Eigen::Vector3d r;
    ASSERT_TRUE(f.Evaluate(at.Pointers(scene_.skeleton, site.bone).data(), r.data(), nullptr));
    EXPECT_LT(r.norm(), 1e-9);
    CalibrationBlocks away{testing::Perturb(truth_, 0.2, 0.1, &rng_), {{0.1, 0.0, -0.1}, {0.3}}};
    ExpectAllJacobiansCorrect(f, away.Pointers(scene_.skeleton, site.bone));
    ASSERT_TRUE(f.Evaluate(away.Pointers(scene_.skeleton, site.bone).data(), r.data(), nullptr));
    EXPECT_GT(r.norm(), 1.0);
  }
}

TEST_F(ResidualsTest, PositionWithConfidenceWeighting) {
  const Camera& cam = scene_.rig.cameras[0];
  int checked = 0;
  for (const Site& site : scene_.layout.sites) {
    Eigen::Vector2d px;
    if (!cam.Project(pose_.position[site.bone] + pose_.rotation[site.bone] * site.offset, &px))
      continue;
    PositionResidual f(fk_.get(), &cam, site, px, 0.8, 0.04);
    ExpectJacobianCorrect(f, ChainOf(scene_.skeleton, site.bone),
                          testing::Perturb(truth_, 0.1, 0.05, &rng_));
    ExpectZeroAtTruthAndGrowing(f, ChainOf(scene_.skeleton, site.bone), truth_, &rng_);
    ++checked;
  }
  EXPECT_GT(checked, 20);
  // The residual scales with sqrt(lambda * c).
  const Site& site = scene_.layout.sites[0];
  Eigen::Vector2d px;
  ASSERT_TRUE(
      cam.Project(pose_.position[site.bone] + pose_.rotation[site.bone] * site.offset, &px));
  PositionResidual full(fk_.get(), &cam, site, px + Eigen::Vector2d(3, 4), 1.0, 1.0);
  PositionResidual quarter(fk_.get(), &cam, site, px + Eigen::Vector2d(3, 4), 0.5, 0.5);
  EXPECT_NEAR(SquaredNorm(full, ChainOf(scene_.skeleton, site.bone), truth_), 25.0, 1e-6);
  EXPECT_NEAR(SquaredNorm(quarter, ChainOf(scene_.skeleton, site.bone), truth_), 25.0 / 4.0, 1e-6);
}

TEST_F(ResidualsTest, AccelerationMatchesTheSecondDifference) {
  const Eigen::VectorXd theta0 = testing::Perturb(truth_, 0.02, 0.01, &rng_);
  const Eigen::VectorXd theta1 = testing::Perturb(truth_, 0.01, 0.005, &rng_);
  BodyPose p0, p1;
  ForwardKinematics(scene_.skeleton, theta0.data(), &p0);
  ForwardKinematics(scene_.skeleton, theta1.data(), &p1);
  const double h1 = 1.0 / 60.0, h2 = 1.1 / 60.0;  // jittered steps
  for (const ImuSite& site : scene_.imus) {
    auto at = [&](const BodyPose& p) {
      return Eigen::Vector3d(p.position[site.bone] + p.rotation[site.bone] * site.offset);
    };
    const Eigen::Vector3d x0 = at(p0), x1 = at(p1), x2 = at(pose_);
    const Eigen::Vector3d expected = 2.0 * ((x2 - x1) / h2 - (x1 - x0) / h1) / (h1 + h2);
    AccelerationResidual f(fk_.get(), site, x1, x0, h1, h2, expected, 0.1);
    ExpectJacobianCorrect(f, ChainOf(scene_.skeleton, site.bone),
                          testing::Perturb(truth_, 0.1, 0.05, &rng_));
    ExpectZeroAtTruthAndGrowing(f, ChainOf(scene_.skeleton, site.bone), truth_, &rng_);
  }
  // Uniform steps reduce to the slide's (x2 - 2 x1 + x0) / dt^2.
  const ImuSite& site = scene_.imus[0];
  const Eigen::Vector3d x1(1.1, 2, 3), x0(1.3, 2, 3);
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(66);
  BodyPose rest;
  ForwardKinematics(scene_.skeleton, theta.data(), &rest);
  const Eigen::Vector3d xs = rest.position[site.bone] + site.offset;
  const double dt = 0.01;
  AccelerationResidual uniform(fk_.get(), site, x1, x0, dt, dt, Eigen::Vector3d::Zero(), 1.0);
  Eigen::Vector3d r;
  ASSERT_TRUE(uniform.Evaluate(ChainBlocks(scene_.skeleton, site.bone, theta.data()).data(),
                               r.data(), nullptr));
  EXPECT_LT((r - (xs - 2 * x1 + x0) / (dt * dt)).norm(), 1e-6);
}

// E_M: zero where the point moves on at its velocity, E_A's residual with no acceleration.
TEST_F(ResidualsTest, MotionCostsTheSecondDifferenceAgainstConstantVelocity) {
  const Eigen::VectorXd theta1 = testing::Perturb(truth_, 0.01, 0.005, &rng_);
  BodyPose p1;
  ForwardKinematics(scene_.skeleton, theta1.data(), &p1);
  const double h1 = 1.0 / 60.0, h2 = 1.1 / 60.0, weight = 1.0 / (55.0 * 55.0);
  std::vector<Site> sites = scene_.layout.sites;
  for (int b = 0; b < scene_.skeleton.num_bones(); ++b) sites.push_back({b, {0, 0, 0}});
  for (const Site& site : sites) {
    auto at = [&](const BodyPose& p) {
      return Eigen::Vector3d(p.position[site.bone] + p.rotation[site.bone] * site.offset);
    };
    const Eigen::Vector3d x1 = at(p1), v = (at(pose_) - x1) / h2;  // on course to the truth
    MotionResidual f(fk_.get(), site, x1, v, h1, h2, weight);
    ExpectJacobianCorrect(f, ChainOf(scene_.skeleton, site.bone),
                          testing::Perturb(truth_, 0.1, 0.05, &rng_));
    ExpectZeroAtTruthAndGrowing(f, ChainOf(scene_.skeleton, site.bone), truth_, &rng_);
  }
  // Elsewhere: E_A's second difference with x(t0) = x(t1) - v h1 and no acceleration.
  Eigen::VectorXd theta = testing::Perturb(truth_, 0.2, 0.1, &rng_);
  for (const ImuSite& imu : scene_.imus) {
    const Site site{imu.bone, imu.offset};
    const Eigen::Vector3d x1 = p1.position[imu.bone] + p1.rotation[imu.bone] * imu.offset;
    const Eigen::Vector3d v(0.4, -1.2, 0.3);
    MotionResidual motion(fk_.get(), site, x1, v, h1, h2, weight);
    AccelerationResidual acceleration(fk_.get(), imu, x1, x1 - v * h1, h1, h2,
                                      Eigen::Vector3d::Zero(), weight);
    Eigen::Vector3d rm, ra;
    const auto blocks = ChainBlocks(scene_.skeleton, imu.bone, theta.data());
    ASSERT_TRUE(motion.Evaluate(blocks.data(), rm.data(), nullptr));
    ASSERT_TRUE(acceleration.Evaluate(blocks.data(), ra.data(), nullptr));
    EXPECT_LT((rm - ra).norm(), 1e-9 * ra.norm()) << imu.name;
  }
  // Uniform steps: sqrt(lambda) (x - 2 x1 + x0) / dt^2 with v = (x1 - x0) / dt.
  const Site root{0, {0, 0, 0}};
  const Eigen::Vector3d x1(1.1, 2, 3), x0(1.3, 2, 3.1);
  const double dt = 0.01;
  MotionResidual uniform(fk_.get(), root, x1, (x1 - x0) / dt, dt, dt, 4.0);
  Eigen::Vector3d r;
  ASSERT_TRUE(
      uniform.Evaluate(ChainBlocks(scene_.skeleton, 0, theta.data()).data(), r.data(), nullptr));
  const Eigen::Vector3d x = theta.head<3>();  // the root's origin
  EXPECT_LT((r - 2.0 * (x - 2 * x1 + x0) / (dt * dt)).norm(), 1e-6);
}

// E_G: sqrt(lambda) times the contact site's height above the floor, zero on it.
TEST_F(ResidualsTest, GroundCostsTheContactSiteHeightAboveTheFloor) {
  const std::vector<Site> contacts = FootContactSites(scene_.skeleton);
  ASSERT_EQ(contacts.size(), 6u);
  const double weight = 1.0 / (0.02 * 0.02);
  for (const Site& site : contacts) {
    const double z = (pose_.position[site.bone] + pose_.rotation[site.bone] * site.offset).z();
    GroundResidual on_floor(fk_.get(), site, z, weight);
    ExpectJacobianCorrect(on_floor, ChainOf(scene_.skeleton, site.bone),
                          testing::Perturb(truth_, 0.2, 0.1, &rng_));
    double r = 1.0;
    ASSERT_TRUE(on_floor.Evaluate(ChainBlocks(scene_.skeleton, site.bone, truth_.data()).data(), &r,
                                  nullptr));
    EXPECT_LT(std::abs(r), 1e-12);
    // 3 cm above a floor at z - 0.03: 1.5 sigma; the root raised 10 cm adds 5 sigma.
    GroundResidual below(fk_.get(), site, z - 0.03, weight);
    Eigen::VectorXd raised = truth_;
    raised[2] += 0.1;
    for (const auto& [theta, expected] : {std::pair{truth_, 1.5}, std::pair{raised, 6.5}}) {
      Eigen::VectorXd t = theta;
      ASSERT_TRUE(
          below.Evaluate(ChainBlocks(scene_.skeleton, site.bone, t.data()).data(), &r, nullptr));
      EXPECT_NEAR(r, expected, 1e-9);
    }
  }
}

TEST_F(ResidualsTest, PointTermAndFitToPoints) {
  std::vector<Site> sites;
  std::vector<Eigen::Vector3d> targets;
  for (const Site& site : scene_.layout.sites) {
    sites.push_back(site);
    targets.push_back(pose_.position[site.bone] + pose_.rotation[site.bone] * site.offset);
    PointResidual f(fk_.get(), site, targets.back(), 4.0);
    ExpectJacobianCorrect(f, ChainOf(scene_.skeleton, site.bone),
                          testing::Perturb(truth_, 0.2, 0.1, &rng_));
    ExpectZeroAtTruthAndGrowing(f, ChainOf(scene_.skeleton, site.bone), truth_, &rng_);
  }
  // Exact targets of every site, from 10 degrees away: the sites come back.
  Eigen::VectorXd theta = testing::Perturb(truth_, 10 * M_PI / 180, 0.05, &rng_);
  std::vector<double> weights(sites.size(), 1.0);
  weights[0] = std::nan("");  // ignored, not fatal
  ASSERT_TRUE(FitToPoints(scene_.skeleton, sites, targets, weights, 50, &theta));
  EXPECT_LT(testing::MaxSiteError(scene_, theta, truth_), 1e-6);
  EXPECT_FALSE(FitToPoints(scene_.skeleton, sites, targets, std::vector<double>(sites.size(), 0.0),
                           50, &theta));
}

TEST_F(ResidualsTest, PcaTermsAreZeroAtTheMeanAndMatchTheirDefinition) {
  const PosePrior prior = testing::RandomPrior(60, 23, truth_, &rng_);
  PcaProjectionResidual proj(prior, 2.0);
  PcaDeviationResidual dev(prior, 3.0);
  EXPECT_EQ(proj.num_residuals(), 60 - 23);
  const BlocksOf joints = JointsOf(scene_.skeleton);
  for (const ceres::CostFunction* f :
       std::initializer_list<const ceres::CostFunction*>{&proj, &dev}) {
    ExpectJacobianCorrect(*f, joints, testing::Perturb(truth_, 0.2, 0.1, &rng_));
    ExpectZeroAtTruthAndGrowing(*f, joints, truth_, &rng_);
  }
  // Against the slide's formulas, written out densely.
  const Eigen::VectorXd theta = testing::Perturb(truth_, 0.3, 0.0, &rng_);
  const Eigen::VectorXd v = theta.tail(60) - prior.mean;
  const Eigen::MatrixXd m = prior.basis;
  const double e_pp = 2.0 * (v - m * m.transpose() * v).squaredNorm();
  const double e_pd =
      3.0 * (prior.sigma.cwiseInverse().asDiagonal() * m.transpose() * v).squaredNorm();
  EXPECT_NEAR(SquaredNorm(proj, joints, theta), e_pp, 1e-9 * e_pp);
  EXPECT_NEAR(SquaredNorm(dev, joints, theta), e_pd, 1e-9 * e_pd);
  // A pose inside the subspace costs nothing in projection, but deviates.
  Eigen::VectorXd inside = truth_;
  inside.tail(60) += 0.3 * m.col(0);
  EXPECT_LT(SquaredNorm(proj, joints, inside), kZeroAtTruth);
  EXPECT_NEAR(SquaredNorm(dev, joints, inside), 3.0 * std::pow(0.3 / prior.sigma(0), 2), 1e-9);
}

}  // namespace
}  // namespace mocap
