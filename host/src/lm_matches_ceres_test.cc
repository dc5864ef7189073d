// lm_solver.h against ceres::Solve (DENSE_NORMAL_CHOLESKY, the frame solver's former set-up)
// on the same residual blocks: random nonlinear blocks over overlapping parameter blocks in
// any order, and a real frame's FrameProblem in the test studio. After one or a few
// iterations the two agree to rounding: a wrong block of J^T J, robust correction, damping
// or step acceptance would show there. Known answers: lm_solver_test.cc.
#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "frame_problem.h"
#include "frame_validation.h"
#include "lm_solver.h"
#include "mocap/residuals/pca_prior_residuals.h"
#include "synthetic_scene.h"

namespace mocap {
namespace {

LmOptions Tight(int max_iterations) {
  LmOptions o;
  o.max_iterations = max_iterations;
  o.function_tolerance = 1e-14;
  o.gradient_tolerance = 1e-14;
  o.parameter_tolerance = 1e-14;
  return o;
}

// ceres::Solve of the problem's residual blocks from x with o's limit and tolerances.
ceres::Solver::Summary SolveWithCeres(const LmProblem& problem, const LmOptions& o,
                                      Eigen::VectorXd* x) {
  ceres::Problem::Options borrow;
  borrow.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  borrow.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem ceres_problem(borrow);
  for (int i = 0; i < problem.num_residual_blocks(); ++i) {
    std::vector<double*> blocks;
    for (int offset : problem.offsets(i)) blocks.push_back(x->data() + offset);
    ceres_problem.AddResidualBlock(const_cast<ceres::CostFunction*>(problem.cost_function(i)),
                                   const_cast<ceres::LossFunction*>(problem.loss_function(i)),
                                   blocks);
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  options.max_num_iterations = o.max_iterations;
  options.function_tolerance = o.function_tolerance;
  options.gradient_tolerance = o.gradient_tolerance;
  options.parameter_tolerance = o.parameter_tolerance;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &ceres_problem, &summary);
  return summary;
}

// r = A sin(B z + c) - d, z the residual's parameter blocks end to end.
class SineResidual : public ceres::CostFunction {
 public:
  SineResidual(int m, const std::vector<int>& sizes, std::mt19937* rng) {
    set_num_residuals(m);
    *mutable_parameter_block_sizes() = sizes;
    int n = 0;
    for (int s : sizes) n += s;
    std::normal_distribution<double> normal;
    auto random = [&](int rows, int cols) {
      return Eigen::MatrixXd::NullaryExpr(rows, cols, [&]() { return normal(*rng); });
    };
    a_ = random(m, m + 2);
    b_ = random(m + 2, n) / std::sqrt(n);
    c_ = random(m + 2, 1);
    d_ = random(m, 1);
  }
  bool Evaluate(double const* const* p, double* r, double** j) const override {
    Eigen::VectorXd z(b_.cols());
    for (int k = 0, at = 0; k < static_cast<int>(parameter_block_sizes().size()); ++k) {
      const int size = parameter_block_sizes()[k];
      z.segment(at, size) = Eigen::Map<const Eigen::VectorXd>(p[k], size);
      at += size;
    }
    const Eigen::VectorXd u = b_ * z + c_;
    Eigen::Map<Eigen::VectorXd>(r, a_.rows()) = a_ * u.array().sin().matrix() - d_;
    if (j == nullptr) return true;
    const Eigen::MatrixXd jz = a_ * u.array().cos().matrix().asDiagonal() * b_;
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    for (int k = 0, at = 0; k < static_cast<int>(parameter_block_sizes().size()); ++k) {
      const int size = parameter_block_sizes()[k];
      if (j[k] != nullptr) Eigen::Map<RowMajor>(j[k], a_.rows(), size) = jz.middleCols(at, size);
      at += size;
    }
    return true;
  }

 private:
  Eigen::MatrixXd a_, b_, c_, d_;
};

// r = A z - d, linear: J^T J = A^T A whatever z (gram()).
class LinearResidual : public ceres::CostFunction {
 public:
  LinearResidual(int m, const std::vector<int>& sizes, std::mt19937* rng) {
    set_num_residuals(m);
    *mutable_parameter_block_sizes() = sizes;
    std::normal_distribution<double> normal;
    a_ = Eigen::MatrixXd::NullaryExpr(m, 15, [&]() { return normal(*rng); });
    a_.conservativeResize(m, std::accumulate(sizes.begin(), sizes.end(), 0));
    d_ = Eigen::VectorXd::NullaryExpr(m, [&]() { return normal(*rng); });
    gram_ = a_.transpose() * a_;
  }
  bool Evaluate(double const* const* p, double* r, double** j) const override {
    Eigen::Map<Eigen::VectorXd> out(r, a_.rows());
    out = -d_;
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    for (int k = 0, at = 0; k < static_cast<int>(parameter_block_sizes().size()); ++k) {
      const int size = parameter_block_sizes()[k];
      out += a_.middleCols(at, size) * Eigen::Map<const Eigen::VectorXd>(p[k], size);
      if (j != nullptr && j[k] != nullptr)
        Eigen::Map<RowMajor>(j[k], a_.rows(), size) = a_.middleCols(at, size);
      at += size;
    }
    return true;
  }
  const Eigen::MatrixXd& gram() const { return gram_; }

 private:
  Eigen::MatrixXd a_, gram_;
  Eigen::VectorXd d_;
};

// rho(s) = s + s^2 / 2: rho'' > 0, where the second-order correction applies.
class ConvexLoss : public ceres::LossFunction {
 public:
  void Evaluate(double s, double out[3]) const override {
    out[0] = s + 0.5 * s * s;
    out[1] = 1.0 + s;
    out[2] = 1.0;
  }
};

// Blocks of 6, 3, 3, 3 (as the root and joints) under 40 residual blocks of 1-5 rows, each
// over 1-4 of them in a random order, with each kind of loss, and 4 linear blocks given
// their Gram (used with the trivial loss, ignored with Cauchy's).
struct RandomProblem {
  explicit RandomProblem(std::mt19937* rng) : problem(15) {
    const ceres::LossFunction* losses[4] = {nullptr, &cauchy, &huber, &convex};
    for (int i = 0; i < 44; ++i) {
      std::vector<int> order = {0, 1, 2, 3};
      std::shuffle(order.begin(), order.end(), *rng);
      order.resize(1 + (*rng)() % 4);
      std::vector<int> offsets, sizes;
      for (int k : order) offsets.push_back(k == 0 ? 0 : 3 + 3 * k), sizes.push_back(k ? 3 : 6);
      const int rows = 1 + (*rng)() % 5;
      if (i < 40) {
        costs.push_back(std::make_unique<SineResidual>(rows, sizes, rng));
        problem.AddResidualBlock(costs.back().get(), losses[i % 4], offsets);
      } else {
        linear.push_back(std::make_unique<LinearResidual>(rows, sizes, rng));
        problem.AddResidualBlock(linear.back().get(), i % 2 ? &cauchy : nullptr, offsets,
                                 &linear.back()->gram());
      }
    }
  }
  ceres::CauchyLoss cauchy{0.5};
  ceres::HuberLoss huber{0.5};
  ConvexLoss convex;
  std::vector<std::unique_ptr<ceres::CostFunction>> costs;
  std::vector<std::unique_ptr<LinearResidual>> linear;
  LmProblem problem;
};

TEST(LmMatchesCeres, RandomBlocksStepByStep) {
  std::mt19937 rng(17);
  for (int trial = 0; trial < 5; ++trial) {
    RandomProblem random(&rng);
    const Eigen::VectorXd start = Eigen::VectorXd::Random(15);
    for (int iterations : {1, 2, 4, 100}) {
      Eigen::VectorXd ours = start, theirs = start;
      const LmSummary s = SolveLm(Tight(iterations), &random.problem, ours.data());
      const ceres::Solver::Summary c = SolveWithCeres(random.problem, Tight(iterations), &theirs);
      ASSERT_NE(s.termination, LmTermination::kFailed) << s.message;
      if (iterations < 100) EXPECT_EQ(s.iterations, static_cast<int>(c.iterations.size()) - 1);
      EXPECT_NEAR(s.final_cost, c.final_cost, 1e-9 * c.final_cost);
      // Run to convergence, the two stop within the tolerances of a flat minimum.
      EXPECT_LT((ours - theirs).lpNorm<Eigen::Infinity>(), iterations < 100 ? 1e-10 : 1e-5)
          << "trial " << trial << ", " << iterations << " iterations";
    }
  }
}

// A frame of the test studio from 10 degrees away: 8 cameras, the keypoints with 2 px of
// noise and one in 15 moved 80 px (the Cauchy loss' tail), 13 IMUs with E_R and E_A, and
// the shipped prior's two terms.
struct StudioFrame {
  StudioFrame() {
    std::mt19937 rng(29);
    truth = testing::RandomPose(scene.skeleton, &rng, 0.4);
    start = testing::Perturb(truth, 10.0 * M_PI / 180.0, 0.05, &rng);
    InputCounts counts;
    clean = ValidateFrame(testing::Render(scene, truth, 0.0), scene.rig, scene.layout, scene.imus,
                          options, &counts);
    std::normal_distribution<double> noise(0.0, 2.0);
    for (size_t k = 0; k < clean.detections.size(); ++k) {
      clean.detections[k].pixel += Eigen::Vector2d(noise(rng), noise(rng));
      if (k % 15 == 0) clean.detections[k].pixel += Eigen::Vector2d(80.0, -50.0);
    }
    std::string error;
    EXPECT_TRUE(LoadPosePriorJson(testing::DataPath("prior_default.json"), &prior, &error));
    projection = std::make_unique<PcaProjectionResidual>(prior, options.pca_projection.weight);
    deviation = std::make_unique<PcaDeviationResidual>(prior, options.pca_deviation.weight);
  }

  void AddTerms(FrameProblem* p) const {
    p->AddPositionTerms(scene.rig, scene.layout, clean.detections, options.position);
    BodyPose pose;
    ForwardKinematics(scene.skeleton, truth.data(), &pose);
    const double h = 1.0 / 60.0;
    for (size_t i = 0; i < scene.imus.size(); ++i) {
      const ImuSite& site = scene.imus[i];
      p->AddOrientationTerm(site, *clean.imu_world[i], options.orientation);
      const Eigen::Vector3d x1 = pose.position[site.bone] + pose.rotation[site.bone] * site.offset;
      const Eigen::Vector3d velocity(0.5, -0.2, 0.1 * i);
      p->AddAccelerationTerm(site, x1, x1 - h * velocity, h, h, Eigen::Vector3d(1.0, 2.0, -3.0),
                             options.acceleration);
    }
    p->AddPriorTerm(kPcaProjectionTerm, projection.get(), options.pca_projection);
    p->AddPriorTerm(kPcaDeviationTerm, deviation.get(), options.pca_deviation);
  }

  testing::Scene scene = testing::MakeScene(8);
  SolverOptions options;
  CleanFrame clean;
  PosePrior prior;
  std::unique_ptr<PcaProjectionResidual> projection;
  std::unique_ptr<PcaDeviationResidual> deviation;
  Eigen::VectorXd truth, start;
};

double Sum(const TermCosts& c) {
  return c.orientation + c.position + c.acceleration + c.pca_projection + c.pca_deviation;
}

TEST(LmMatchesCeres, StudioFrameStepByStep) {
  const StudioFrame frame;
  for (int iterations : {1, 2, 3}) {
    Eigen::VectorXd ours = frame.start, theirs = frame.start;
    FrameProblem problem(frame.scene.skeleton, ours.data());
    frame.AddTerms(&problem);
    ASSERT_EQ(problem.count(kPositionTerm), 8 * 33);
    const LmSummary s = problem.Solve(Tight(iterations));
    const ceres::Solver::Summary c = SolveWithCeres(problem.problem(), Tight(iterations), &theirs);
    EXPECT_EQ(s.termination, LmTermination::kIterationLimit) << s.message;
    EXPECT_LT((ours - theirs).lpNorm<Eigen::Infinity>(), 1e-10) << iterations << " iterations";
    EXPECT_NEAR(s.final_cost, c.final_cost, 1e-10 * c.final_cost);
    // The per-term costs at the solution are the terms' rho(|r|^2) (Ceres' cost is half).
    EXPECT_NEAR(Sum(problem.Costs()), 2.0 * c.final_cost, 1e-9 * c.final_cost);
  }
}

// With the solver's own options (function_tolerance 1e-3, at most 10 iterations), the same
// iterations end at the same pose: the tolerances keep the meaning they were tuned with.
TEST(LmMatchesCeres, StudioFrameWithTheSolversTolerances) {
  const StudioFrame frame;
  Eigen::VectorXd ours = frame.start, theirs = frame.start;
  FrameProblem problem(frame.scene.skeleton, ours.data());
  frame.AddTerms(&problem);
  LmOptions o;
  o.max_iterations = frame.options.max_iterations;
  o.function_tolerance = frame.options.function_tolerance;
  o.gradient_tolerance = frame.options.gradient_tolerance;
  o.parameter_tolerance = frame.options.parameter_tolerance;
  const LmSummary s = problem.Solve(o);
  const ceres::Solver::Summary c = SolveWithCeres(problem.problem(), o, &theirs);
  EXPECT_EQ(s.termination, LmTermination::kConverged) << s.message;
  EXPECT_EQ(c.termination_type, ceres::CONVERGENCE);
  EXPECT_EQ(s.iterations, static_cast<int>(c.iterations.size()) - 1);
  EXPECT_LT((ours - theirs).lpNorm<Eigen::Infinity>(), 1e-10);
  EXPECT_LT(s.final_cost, 0.5 * s.initial_cost);
}

}  // namespace
}  // namespace mocap
