// Levenberg-Marquardt for the per-frame pose: residual blocks (ceres::CostFunction with
// analytic Jacobians, optional ceres::LossFunction) over segments of one parameter vector x.
// A residual on bone b touches only the blocks of b's chain (kinematics.h), so the residual
// blocks over the same parameter blocks (the keypoints and sensors of one bone) form a group
// whose stacked Jacobian has only its chain's columns (24 at most of the pose's 66); the
// normal equations J^T J are one symmetric product per group, added into the dense
// num_parameters x num_parameters matrix block pair by block pair. Internal to the solver.
//
// The iteration is Ceres' trust-region Levenberg-Marquardt with its defaults, so the
// solver's tolerances keep the meaning and the tuning they were given on Ceres:
//   cost C(x) = 1/2 sum_i rho_i(|r_i|^2), gradient g = J^T r, H = J^T J (of the corrected r,
//   J: lm_problem.cc), step (H + D / radius) dx = -g with D = diag(H) clamped to
//   [min_diagonal, max_diagonal] in Jacobi-scaled columns (scale 1 / (1 + |column|) at the
//   start). A step is taken when q = (C(x) - C(x + dx)) / (its model's decrease) exceeds
//   min_relative_decrease; the radius then grows by 1 / max(1/3, 1 - (2 q - 1)^3), else it
//   shrinks by 2, 4, 8, ... A step whose cost cannot be evaluated (a residual returns false,
//   or the cost is not finite) is rejected like one that raises the cost; one the damped
//   equations give no descent for (Cholesky fails, the model does not decrease) likewise,
//   up to max_consecutive_invalid_steps in a row (then kFailed). It stops, converged, when
//   |C(x) - C(x + dx)| <= function_tolerance C(x) or |dx| <= parameter_tolerance
//   (|x| + parameter_tolerance) (that step is not taken, as in Ceres), when
//   max |g| <= gradient_tolerance, or when the radius falls below min_radius; with
//   kIterationLimit after max_iterations steps; with kFailed when the residuals or
//   Jacobians at x itself cannot be evaluated or are not finite.
#ifndef MOCAP_SRC_LM_SOLVER_H_
#define MOCAP_SRC_LM_SOLVER_H_

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>

#include <Eigen/Core>
#include <string>
#include <vector>

namespace mocap {

struct LmOptions {
  int max_iterations = 50;
  double function_tolerance = 1e-6;
  double gradient_tolerance = 1e-10;
  double parameter_tolerance = 1e-8;
  double initial_radius = 1e4;
  double max_radius = 1e16;
  double min_radius = 1e-32;
  double min_relative_decrease = 1e-3;
  double min_diagonal = 1e-6;
  double max_diagonal = 1e32;
  int max_consecutive_invalid_steps = 5;
};

enum class LmTermination { kConverged, kIterationLimit, kFailed };

struct LmSummary {
  LmTermination termination = LmTermination::kFailed;
  std::string message;
  // Steps accepted or rejected; as in Ceres, the step whose smallness ends the solve is not
  // counted.
  int iterations = 0;
  int accepted = 0;                         // of which accepted
  double initial_cost = 0, final_cost = 0;  // C(x) = 1/2 sum rho
  // Milliseconds: all of it, normal equations (J^T J, J^T r) and their factorisation,
  // residuals with Jacobians, residuals alone (candidate steps).
  double total_ms = 0, linear_solver_ms = 0, jacobian_ms = 0, residual_ms = 0;
};

class LmProblem {
 public:
  explicit LmProblem(int num_parameters);

  // A residual block over the parameter blocks x[offsets[k] : offsets[k] + size_k], sizes
  // cost->parameter_block_sizes(); the blocks of one residual must not overlap. cost and
  // loss (null: trivial, rho(s) = s) are borrowed. gram, when given, is the cost's J^T J
  // (its Jacobian does not depend on x, as a linear residual's): with a trivial loss it is
  // added as it is instead of being accumulated at every linearisation. Returns its index,
  // or -1 (nothing added) when the offsets do not fit the cost's blocks into x or the Gram
  // is not of their size.
  int AddResidualBlock(const ceres::CostFunction* cost, const ceres::LossFunction* loss,
                       const std::vector<int>& offsets, const Eigen::MatrixXd* gram = nullptr);

  int num_parameters() const { return num_parameters_; }
  int num_residual_blocks() const { return static_cast<int>(blocks_.size()); }
  const ceres::CostFunction* cost_function(int i) const { return blocks_[i].cost; }
  const ceres::LossFunction* loss_function(int i) const { return blocks_[i].loss; }
  std::vector<int> offsets(int i) const;

  // C(x); false when a residual block fails or C is not finite.
  bool Cost(const double* x, double* cost);
  // Residuals and Jacobians at x, corrected for the losses (lm_problem.cc), and each
  // block's rho(|r|^2); false as Cost.
  bool Linearize(const double* x, double* cost);
  // The last Linearize's normal equations: the upper triangle of J^T J (the rest of it is
  // not meaningful) and J^T r.
  void NormalEquations(Eigen::MatrixXd* jtj, Eigen::VectorXd* jtr);
  // rho(|r_i|^2) of each block at x (infinite for a block that fails there).
  void EvaluateBlockCosts(const double* x);
  // rho(|r_i|^2) of block i at costs_at(): the point of the last Linearize or
  // EvaluateBlockCosts (empty before either).
  double block_cost(int i) const { return rho_[i]; }
  const Eigen::VectorXd& costs_at() const { return costs_at_; }

 private:
  struct Block {
    const ceres::CostFunction* cost;
    const ceres::LossFunction* loss;
    int num_residuals, num_parameter_blocks;
    int first_parameter_block;  // into offsets_, sizes_
    int group, row;             // its group and first row there
  };
  // Blocks over the same parameter blocks in the same order (and all with or all without a
  // used Gram). Residuals: `rows` from residual_start; Jacobian: rows x columns,
  // column-major, from jacobian_start.
  struct Group {
    int first_parameter_block, num_parameter_blocks;  // those of its first block
    bool gram;
    int rows = 0, columns = 0, residual_start = 0, jacobian_start = 0;
    std::vector<const Eigen::MatrixXd*> grams;
  };
  int GroupOf(const std::vector<int>& offsets, bool gram);
  // Places the groups' rows in the residual and Jacobian buffers (after blocks were added).
  void Layout();
  // Evaluates a block at x into `residuals` (and its Jacobian into jacobian_blocks_): rho,
  // rho', rho'' of its |r|^2. False when the cost function fails or rho is not finite.
  bool EvaluateBlock(const Block& block, const double* x, double* residuals, bool jacobian,
                     double rho[3]);
  // Replaces the block's residuals r by their robust-loss corrections and puts its
  // corrected Jacobian into its group's.
  void Correct(const Block& block, double squared_norm, const double rho[3], double* r);
  void AddGroup(const Group& group, Eigen::MatrixXd* jtj, Eigen::VectorXd* jtr);

  int num_parameters_;
  bool laid_out_ = false;
  std::vector<Block> blocks_;
  std::vector<Group> groups_;
  std::vector<int> offsets_, sizes_;
  std::vector<std::vector<int>> groups_by_first_offset_;
  Eigen::VectorXd residuals_, jacobians_;
  std::vector<double> rho_;
  std::vector<double> scratch_;            // residuals of a cost-only evaluation
  std::vector<const double*> parameters_;  // scratch: one block's parameter pointers
  std::vector<double*> jacobian_blocks_;   // scratch: one block's Jacobian pointers
  std::vector<double> block_jacobian_;     // scratch: one block's Jacobian
  Eigen::MatrixXd gram_;                   // scratch: one group's J^T J
  Eigen::VectorXd gradient_;               // scratch: one group's J^T r
  Eigen::VectorXd costs_at_;
};

// Minimises C over x, from x (updated in place; it is the last accepted point whatever the
// termination).
LmSummary SolveLm(const LmOptions& options, LmProblem* problem, double* x);

}  // namespace mocap

#endif  // MOCAP_SRC_LM_SOLVER_H_
