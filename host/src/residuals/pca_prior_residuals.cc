#include "mocap/residuals/pca_prior_residuals.h"

#include <Eigen/QR>
#include <cmath>

namespace mocap {

LinearPriorResidual::LinearPriorResidual(const PosePrior& prior, Eigen::MatrixXd a)
    : mean_(prior.mean), a_(std::move(a)), gram_(a_.transpose() * a_) {
  set_num_residuals(static_cast<int>(a_.rows()));
  mutable_parameter_block_sizes()->assign(prior.dof() / 3, 3);
}

bool LinearPriorResidual::Evaluate(double const* const* parameters, double* residuals,
                                   double** jacobians) const {
  const int blocks = static_cast<int>(mean_.size()) / 3;
  Eigen::VectorXd bar(mean_.size());
  for (int i = 0; i < blocks; ++i)
    bar.segment<3>(3 * i) = Eigen::Map<const Eigen::Vector3d>(parameters[i]);
  Eigen::Map<Eigen::VectorXd> r(residuals, a_.rows());
  r = a_ * (bar - mean_);
  if (jacobians != nullptr) {
    using Block = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
    for (int i = 0; i < blocks; ++i) {
      if (jacobians[i] != nullptr)
        Eigen::Map<Block>(jacobians[i], a_.rows(), 3) = a_.middleCols<3>(3 * i);
    }
  }
  return true;
}

namespace {
// N^T: rows span the orthogonal complement of the basis columns.
Eigen::MatrixXd ComplementTranspose(const Eigen::MatrixXd& basis) {
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(basis);
  const Eigen::MatrixXd q = qr.householderQ();
  return q.rightCols(basis.rows() - basis.cols()).transpose();
}
}  // namespace

PcaProjectionResidual::PcaProjectionResidual(const PosePrior& prior, double weight)
    : LinearPriorResidual(prior, std::sqrt(weight) * ComplementTranspose(prior.basis)) {}

PcaDeviationResidual::PcaDeviationResidual(const PosePrior& prior, double weight)
    : LinearPriorResidual(prior, std::sqrt(weight) * prior.sigma.cwiseInverse().asDiagonal() *
                                     prior.basis.transpose()) {}

}  // namespace mocap
