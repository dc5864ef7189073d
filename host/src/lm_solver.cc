// SolveLm: the trust-region Levenberg-Marquardt iteration (lm_solver.h).
#include "lm_solver.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace mocap {
namespace {

using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

class LevenbergMarquardt {
 public:
  LevenbergMarquardt(const LmOptions& options, LmProblem* problem, double* x)
      : o_(options), problem_(problem), x_(x, problem->num_parameters()) {}

  LmSummary Run();

 private:
  // Residuals, Jacobians and normal equations at x_; false when they are not finite.
  bool Linearize();
  // The damped step dx_ and its model decrease; false when it cannot be used.
  bool ComputeStep();
  enum class Outcome { kAccepted, kRejected, kConverged };
  // Evaluates x + dx and takes it when it lowers the cost enough; kConverged (x kept, the
  // summary finished) when the step or the cost change is below its tolerance.
  Outcome TryStep();
  void Shrink() {
    radius_ /= decrease_factor_;
    decrease_factor_ *= 2.0;
  }
  bool GradientSmall() const { return g_.lpNorm<Eigen::Infinity>() <= o_.gradient_tolerance; }
  LmSummary Finish(LmTermination termination, const char* message);

  const LmOptions& o_;
  LmProblem* problem_;
  Eigen::Map<Eigen::VectorXd> x_;
  LmSummary summary_;
  Clock::time_point start_ = Clock::now();
  double cost_ = 0, radius_ = 0, decrease_factor_ = 2.0, model_decrease_ = 0;
  Eigen::MatrixXd h_, damped_;
  Eigen::VectorXd g_, dx_, hdx_, candidate_, scale_;
  Eigen::LLT<Eigen::MatrixXd, Eigen::Upper> llt_;
};

bool LevenbergMarquardt::Linearize() {
  const Clock::time_point start = Clock::now();
  const bool ok = problem_->Linearize(x_.data(), &cost_);
  summary_.jacobian_ms += MsSince(start);
  if (!ok) return false;
  const Clock::time_point normal = Clock::now();
  problem_->NormalEquations(&h_, &g_);
  summary_.linear_solver_ms += MsSince(normal);
  return g_.allFinite() && h_.diagonal().allFinite();  // a non-finite J shows on H's diagonal
}

bool LevenbergMarquardt::ComputeStep() {
  const Clock::time_point start = Clock::now();
  // Ceres damps diag(J^T J) of the Jacobi-scaled columns, clamped, over the radius; in the
  // unscaled variables that is clamp(s^2 H_ii) / (s^2 radius).
  damped_ = h_;
  for (int i = 0; i < h_.rows(); ++i) {
    const double s2 = scale_[i] * scale_[i];
    damped_(i, i) += std::clamp(s2 * h_(i, i), o_.min_diagonal, o_.max_diagonal) / (s2 * radius_);
  }
  llt_.compute(damped_);
  bool ok = llt_.info() == Eigen::Success;
  if (ok) {
    dx_ = -g_;
    llt_.solveInPlace(dx_);
    ok = dx_.allFinite();
  }
  if (ok) {
    // The decrease of the linearised cost |r + J dx|^2 / 2 (the damping left out).
    hdx_.noalias() = h_.selfadjointView<Eigen::Upper>() * dx_;
    model_decrease_ = -(g_.dot(dx_) + 0.5 * dx_.dot(hdx_));
    ok = model_decrease_ > 0.0;
  }
  summary_.linear_solver_ms += MsSince(start);
  return ok;
}

LevenbergMarquardt::Outcome LevenbergMarquardt::TryStep() {
  candidate_ = x_ + dx_;
  const Clock::time_point start = Clock::now();
  double candidate_cost = 0.0;
  if (!problem_->Cost(candidate_.data(), &candidate_cost)) {
    candidate_cost = std::numeric_limits<double>::infinity();  // rejected below
  }
  summary_.residual_ms += MsSince(start);
  if (dx_.norm() <= o_.parameter_tolerance * (x_.norm() + o_.parameter_tolerance)) {
    Finish(LmTermination::kConverged, "parameter tolerance reached");
    return Outcome::kConverged;
  }
  if (std::abs(cost_ - candidate_cost) <= o_.function_tolerance * cost_) {
    Finish(LmTermination::kConverged, "function tolerance reached");
    return Outcome::kConverged;
  }
  const double quality = (cost_ - candidate_cost) / model_decrease_;
  if (!(quality > o_.min_relative_decrease)) return Outcome::kRejected;
  x_ = candidate_;
  ++summary_.accepted;
  radius_ /= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * quality - 1.0, 3));
  radius_ = std::min(radius_, o_.max_radius);
  decrease_factor_ = 2.0;
  return Outcome::kAccepted;
}

LmSummary LevenbergMarquardt::Run() {
  if (!Linearize())
    return Finish(LmTermination::kFailed, "the residuals cannot be evaluated at the start");
  summary_.initial_cost = cost_;
  scale_ = (1.0 + h_.diagonal().array().sqrt()).inverse();  // Jacobi scaling, fixed at start
  if (GradientSmall()) return Finish(LmTermination::kConverged, "gradient tolerance reached");
  radius_ = o_.initial_radius;
  int invalid_steps = 0;
  while (summary_.iterations < o_.max_iterations) {
    if (!ComputeStep()) {
      if (++invalid_steps >= o_.max_consecutive_invalid_steps)
        return Finish(LmTermination::kFailed, "the damped normal equations cannot be solved");
      Shrink();
    } else {
      invalid_steps = 0;
      const Outcome outcome = TryStep();
      if (outcome == Outcome::kConverged) return summary_;
      if (outcome == Outcome::kRejected) {
        Shrink();
      } else if (!Linearize()) {
        return Finish(LmTermination::kFailed, "the Jacobians cannot be evaluated at a step");
      }
    }
    ++summary_.iterations;
    // (After a rejected step the gradient is the one that did not stop the solve before.)
    if (GradientSmall()) return Finish(LmTermination::kConverged, "gradient tolerance reached");
    if (radius_ <= o_.min_radius)
      return Finish(LmTermination::kConverged, "trust region radius below its minimum");
  }
  return Finish(LmTermination::kIterationLimit, "iteration limit reached");
}

LmSummary LevenbergMarquardt::Finish(LmTermination termination, const char* message) {
  summary_.termination = termination;
  summary_.message = message;
  summary_.final_cost = cost_;
  summary_.total_ms = MsSince(start_);
  return summary_;
}

}  // namespace

LmSummary SolveLm(const LmOptions& options, LmProblem* problem, double* x) {
  return LevenbergMarquardt(options, problem, x).Run();
}

}  // namespace mocap
