// E_PP and E_PD, the PCA pose-prior terms (slide "Pose prior terms"), over the
// non-root DOF theta_bar = theta[6:] (60-D for the default skeleton).
//
// PCA projection: distance of the pose from the prior's subspace
//   |r|^2 = lambda_PP * |(I - M M^T)(theta_bar - mu)|^2
// computed with N, an orthonormal basis of the complement of M's columns, since
// |(I - M M^T) v| = |N^T v|:  r = sqrt(lambda_PP) * N^T (theta_bar - mu)
// (d - k residuals instead of d: the same cost, a smaller Jacobian).
// PCA deviation: the pose's coordinates in the subspace, in standard deviations
//   r = sqrt(lambda_PD) * diag(sigma)^-1 M^T (theta_bar - mu)  (k residuals, unitless)
// Both are linear in theta: the Jacobians are the constant matrices above. The
// parameter blocks are those of bones 1..n-1 (3 each, in bone order): theta_bar.
// E = rho(|r|^2) as the paper.
#ifndef MOCAP_RESIDUALS_PCA_PRIOR_RESIDUALS_H_
#define MOCAP_RESIDUALS_PCA_PRIOR_RESIDUALS_H_

#include <ceres/cost_function.h>

#include <Eigen/Core>

#include "mocap/prior.h"

namespace mocap {

// Shared form r = A (theta_bar - mu) with a constant A.
class LinearPriorResidual : public ceres::CostFunction {
 public:
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;
  // A^T A, the constant J^T J of the normal equations (lm_solver.h), made once.
  const Eigen::MatrixXd& gram() const { return gram_; }

 protected:
  LinearPriorResidual(const PosePrior& prior, Eigen::MatrixXd a);

 private:
  Eigen::VectorXd mean_;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> a_;
  Eigen::MatrixXd gram_;
};

class PcaProjectionResidual : public LinearPriorResidual {
 public:
  // weight: lambda_PP (1/rad^2).
  PcaProjectionResidual(const PosePrior& prior, double weight);
};

class PcaDeviationResidual : public LinearPriorResidual {
 public:
  // weight: lambda_PD (unitless).
  PcaDeviationResidual(const PosePrior& prior, double weight);
};

}  // namespace mocap

#endif  // MOCAP_RESIDUALS_PCA_PRIOR_RESIDUALS_H_
