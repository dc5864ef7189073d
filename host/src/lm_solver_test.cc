// The Levenberg-Marquardt of lm_solver.h on problems with known answers: a curve fit, a
// robust line fit with outliers, a residual undefined on part of the domain, and its
// terminations. Agreement with ceres::Solve: lm_matches_ceres_test.cc.
#include "lm_solver.h"

#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

namespace mocap {
namespace {

LmOptions Tight(int max_iterations = 100) {
  LmOptions o;
  o.max_iterations = max_iterations;
  o.function_tolerance = 1e-14;
  o.gradient_tolerance = 1e-14;
  o.parameter_tolerance = 1e-14;
  return o;
}

// y = exp(m t + c), one parameter block each.
class ExponentialResidual : public ceres::SizedCostFunction<1, 1, 1> {
 public:
  ExponentialResidual(double t, double y) : t_(t), y_(y) {}
  bool Evaluate(double const* const* p, double* r, double** j) const override {
    const double e = std::exp(p[0][0] * t_ + p[1][0]);
    r[0] = e - y_;
    if (j != nullptr && j[0] != nullptr) j[0][0] = e * t_;
    if (j != nullptr && j[1] != nullptr) j[1][0] = e;
    return true;
  }

 private:
  double t_, y_;
};

TEST(LmSolver, FitsAnExponentialExactly) {
  std::vector<std::unique_ptr<ExponentialResidual>> costs;
  LmProblem problem(2);
  for (double t = 0.0; t <= 5.0; t += 0.25) {
    costs.push_back(std::make_unique<ExponentialResidual>(t, std::exp(0.3 * t + 0.1)));
    problem.AddResidualBlock(costs.back().get(), nullptr, {1, 0});  // m is x[1], c is x[0]
  }
  double x[2] = {0.0, 0.0};
  const LmSummary s = SolveLm(Tight(), &problem, x);
  EXPECT_EQ(s.termination, LmTermination::kConverged) << s.message;
  EXPECT_NEAR(x[1], 0.3, 1e-9);
  EXPECT_NEAR(x[0], 0.1, 1e-9);
  EXPECT_LT(s.final_cost, 1e-20);
  EXPECT_GT(s.initial_cost, 1.0);
}

// r = a t + b - y over x = (a, b).
class LineResidual : public ceres::SizedCostFunction<1, 2> {
 public:
  LineResidual(double t, double y) : t_(t), y_(y) {}
  bool Evaluate(double const* const* p, double* r, double** j) const override {
    r[0] = p[0][0] * t_ + p[0][1] - y_;
    if (j != nullptr && j[0] != nullptr) j[0][0] = t_, j[0][1] = 1.0;
    return true;
  }

 private:
  double t_, y_;
};

// The line y = 2 t - 1 through 20 points with 0.01 of noise and 6 outliers 5 above it,
// fitted from x.
void FitLine(const ceres::LossFunction* loss, Eigen::Vector2d* x) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<std::unique_ptr<LineResidual>> costs;
  LmProblem problem(2);
  for (int i = 0; i < 26; ++i) {
    const double t = 0.1 * i;
    const bool outlier = i % 4 == 1 && i < 24;
    costs.push_back(
        std::make_unique<LineResidual>(t, 2.0 * t - 1.0 + (outlier ? 5.0 : noise(rng))));
    problem.AddResidualBlock(costs.back().get(), loss, {0});
  }
  EXPECT_NE(SolveLm(Tight(), &problem, x->data()).termination, LmTermination::kFailed);
}

TEST(LmSolver, CauchyLossIgnoresOutliers) {
  Eigen::Vector2d x(0.0, 0.0);
  FitLine(nullptr, &x);
  // The outliers drag the least-squares line (what the robust loss must undo).
  EXPECT_GT((x - Eigen::Vector2d(2.0, -1.0)).norm(), 0.5);
  ceres::CauchyLoss cauchy(0.1);
  FitLine(&cauchy, &x);  // from the least-squares line, as a warm start would
  EXPECT_NEAR(x[0], 2.0, 0.02);
  EXPECT_NEAR(x[1], -1.0, 0.02);
}

// r = log(x) - log(4): no value for x <= 0, where the first full steps from x = 40 land.
class LogResidual : public ceres::SizedCostFunction<1, 1> {
 public:
  bool Evaluate(double const* const* p, double* r, double** j) const override {
    if (p[0][0] <= 0.0) return false;
    r[0] = std::log(p[0][0] / 4.0);
    if (j != nullptr && j[0] != nullptr) j[0][0] = 1.0 / p[0][0];
    return true;
  }
};

TEST(LmSolver, RejectsStepsWhereAResidualFails) {
  LogResidual cost;
  LmProblem problem(1);
  problem.AddResidualBlock(&cost, nullptr, {0});
  double x = 40.0;  // Gauss-Newton: x - x r = 40 - 40 log(10) < 0
  const LmSummary s = SolveLm(Tight(), &problem, &x);
  EXPECT_EQ(s.termination, LmTermination::kConverged) << s.message;
  EXPECT_NEAR(x, 4.0, 1e-9);
  EXPECT_GT(s.iterations - s.accepted, 2) << "the failing steps were rejected";
}

TEST(LmSolver, FailsWhenTheStartCannotBeEvaluated) {
  LogResidual cost;
  LmProblem problem(1);
  problem.AddResidualBlock(&cost, nullptr, {0});
  double x = -1.0;
  const LmSummary s = SolveLm(Tight(), &problem, &x);
  EXPECT_EQ(s.termination, LmTermination::kFailed);
  EXPECT_EQ(x, -1.0);
}

TEST(LmSolver, RefusesBlocksThatDoNotFitX) {
  ExponentialResidual cost(1.0, 1.0);
  LmProblem problem(2);
  EXPECT_EQ(problem.AddResidualBlock(&cost, nullptr, {0}), -1);     // one offset for two blocks
  EXPECT_EQ(problem.AddResidualBlock(&cost, nullptr, {0, 2}), -1);  // past the end of x
  EXPECT_EQ(problem.AddResidualBlock(&cost, nullptr, {1, -1}), -1);
  const Eigen::MatrixXd gram = Eigen::MatrixXd::Identity(3, 3);  // the blocks have 2 columns
  EXPECT_EQ(problem.AddResidualBlock(&cost, nullptr, {1, 0}, &gram), -1);
  EXPECT_EQ(problem.num_residual_blocks(), 0);
  EXPECT_EQ(problem.AddResidualBlock(&cost, nullptr, {1, 0}), 0);
}

TEST(LmSolver, ReportsTheIterationLimit) {
  LogResidual cost;
  LmProblem problem(1);
  problem.AddResidualBlock(&cost, nullptr, {0});
  double x = 40.0;
  const LmSummary s = SolveLm(Tight(3), &problem, &x);
  EXPECT_EQ(s.termination, LmTermination::kIterationLimit);
  EXPECT_EQ(s.iterations, 3);
}

// At the solution every residual is zero: with a robust loss too (where the correction
// divides by |r|^2) the gradient is zero and no step is taken.
TEST(LmSolver, ConvergedAtTheStartTakesNoStep) {
  LogResidual cost;
  ceres::CauchyLoss cauchy(1.0);
  for (const ceres::LossFunction* loss : {static_cast<const ceres::LossFunction*>(nullptr),
                                          static_cast<const ceres::LossFunction*>(&cauchy)}) {
    LmProblem problem(1);
    problem.AddResidualBlock(&cost, loss, {0});
    double x = 4.0;
    const LmSummary s = SolveLm(Tight(), &problem, &x);
    EXPECT_EQ(s.termination, LmTermination::kConverged) << s.message;
    EXPECT_EQ(s.iterations, 0);
    EXPECT_EQ(x, 4.0);
  }
}

}  // namespace
}  // namespace mocap
