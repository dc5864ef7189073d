// The prediction shift (prediction_shift.h): a shifted motion residual is the motion residual of
// a prediction moved by delta, with a correct Jacobian in the pose and in delta; the prior
// costs delta^T Lambda delta.
#include "mocap/residuals/prediction_shift.h"

#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include <memory>
#include <random>

#include "mocap/residuals/acceleration_residual.h"
#include "mocap/residuals/motion_residual.h"
#include "synthetic_scene.h"

namespace mocap {
namespace {

// The blocks of a residual on `bone` of theta, then delta.
std::vector<double*> Blocks(const Skeleton& s, int bone, Eigen::VectorXd* theta,
                            Eigen::Vector3d* delta) {
  std::vector<double*> blocks = ChainBlocks(s, bone, theta->data());
  blocks.push_back(delta->data());
  return blocks;
}

void ExpectJacobianCorrect(const ceres::CostFunction& f, std::vector<double*> blocks) {
  ceres::NumericDiffOptions numeric;
  const std::vector<const ceres::Manifold*>* no_manifolds = nullptr;
  ceres::GradientChecker checker(&f, no_manifolds, numeric);
  ceres::GradientChecker::ProbeResults results;
  EXPECT_TRUE(checker.Probe(blocks.data(), 1e-5, &results)) << results.error_log;
}

class PredictionShiftTest : public ::testing::Test {
 protected:
  void SetUp() override {
    scene_ = testing::MakeScene(1);
    theta_ = testing::RandomPose(scene_.skeleton, &rng_);
    fk_ = std::make_unique<KinematicsCache>(&scene_.skeleton);
  }
  // r(theta, delta) of `shifted` against r(theta) of `moved` (the prediction moved by delta).
  void ExpectSameAsMoved(const ceres::CostFunction& shifted, const ceres::CostFunction& moved,
                         int bone, Eigen::Vector3d delta) {
    Eigen::VectorXd theta = theta_;
    Eigen::Vector3d a, b;
    ASSERT_TRUE(
        shifted.Evaluate(Blocks(scene_.skeleton, bone, &theta, &delta).data(), a.data(), nullptr));
    ASSERT_TRUE(
        moved.Evaluate(ChainBlocks(scene_.skeleton, bone, theta.data()).data(), b.data(), nullptr));
    EXPECT_LT((a - b).norm(), 1e-9 * (1.0 + b.norm()));
  }
  std::mt19937 rng_{7};
  testing::Scene scene_;
  Eigen::VectorXd theta_;
  std::unique_ptr<KinematicsCache> fk_;
};

TEST_F(PredictionShiftTest, AShiftedMotionTermIsTheTermOfAMovedPrediction) {
  const double h1 = 1 / 60.0, h2 = 1.2 / 60.0, weight = 1.0 / (55.0 * 55.0);
  const Eigen::Vector3d x1(0.2, -0.1, 1.0), v(0.8, 0.1, -0.2), delta(0.03, -0.05, 0.02);
  for (int bone : {0, 8, 16}) {
    const Site site{bone, {0.01, 0.02, -0.03}};
    auto inner = std::make_unique<MotionResidual>(fk_.get(), site, x1, v, h1, h2, weight);
    const double scale = inner->position_scale();
    const ShiftedPrediction shifted(std::move(inner), scale);
    const MotionResidual moved(fk_.get(), site, x1 + delta, v, h1, h2, weight);
    ExpectSameAsMoved(shifted, moved, bone, delta);
    Eigen::VectorXd theta = testing::Perturb(theta_, 0.2, 0.1, &rng_);
    Eigen::Vector3d at(0.1, 0.2, -0.1);
    ExpectJacobianCorrect(shifted, Blocks(scene_.skeleton, bone, &theta, &at));
  }
}

// E_A's prediction moves with x(t1) and x(t0) together: the velocity between them is kept.
TEST_F(PredictionShiftTest, AShiftedAccelerationTermMovesBothPreviousPositions) {
  const double h1 = 1 / 60.0, h2 = 0.9 / 60.0, weight = 1.0 / (18.0 * 18.0);
  const Eigen::Vector3d x1(0.2, -0.1, 1.0), x0(0.19, -0.1, 1.01), a(0.5, -2.0, 1.0);
  const Eigen::Vector3d delta(-0.04, 0.01, 0.06);
  for (const ImuSite& imu : scene_.imus) {
    auto inner = std::make_unique<AccelerationResidual>(fk_.get(), imu, x1, x0, h1, h2, a, weight);
    const double scale = inner->position_scale();
    const ShiftedPrediction shifted(std::move(inner), scale);
    const AccelerationResidual moved(fk_.get(), imu, x1 + delta, x0 + delta, h1, h2, a, weight);
    ExpectSameAsMoved(shifted, moved, imu.bone, delta);
  }
}

TEST_F(PredictionShiftTest, ThePriorCostsTheShiftByItsInformation) {
  Eigen::Matrix3d m = Eigen::Matrix3d::Random();
  const Eigen::Matrix3d information = m * m.transpose() + 0.1 * Eigen::Matrix3d::Identity();
  const PredictionShiftPrior prior(information);
  Eigen::Vector3d delta(0.3, -0.2, 0.5), r;
  double* blocks[] = {delta.data()};
  ASSERT_TRUE(prior.Evaluate(blocks, r.data(), nullptr));
  EXPECT_NEAR(r.squaredNorm(), delta.dot(information * delta), 1e-12);
  ExpectJacobianCorrect(prior, {delta.data()});
}

}  // namespace
}  // namespace mocap
