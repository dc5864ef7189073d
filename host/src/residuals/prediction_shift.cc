#include "mocap/residuals/prediction_shift.h"

#include <Eigen/Cholesky>

namespace mocap {

ShiftedPrediction::ShiftedPrediction(std::unique_ptr<ceres::CostFunction> inner, double scale)
    : inner_(std::move(inner)), scale_(scale) {
  set_num_residuals(inner_->num_residuals());
  *mutable_parameter_block_sizes() = inner_->parameter_block_sizes();
  mutable_parameter_block_sizes()->push_back(3);
}

bool ShiftedPrediction::Evaluate(double const* const* parameters, double* residuals,
                                 double** jacobians) const {
  if (!inner_->Evaluate(parameters, residuals, jacobians)) return false;
  const int shift = static_cast<int>(inner_->parameter_block_sizes().size());
  const Eigen::Map<const Eigen::Vector3d> delta(parameters[shift]);
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r -= scale_ * delta;
  if (jacobians != nullptr && jacobians[shift] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> j(jacobians[shift]);
    j = -scale_ * Eigen::Matrix3d::Identity();
  }
  return true;
}

PredictionShiftPrior::PredictionShiftPrior(const Eigen::Matrix3d& information) {
  set_num_residuals(3);
  mutable_parameter_block_sizes()->push_back(3);
  u_ = Eigen::LLT<Eigen::Matrix3d>(information).matrixU();
}

bool PredictionShiftPrior::Evaluate(double const* const* parameters, double* residuals,
                                    double** jacobians) const {
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = u_ * Eigen::Map<const Eigen::Vector3d>(parameters[0]);
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> j(jacobians[0]);
    j = u_;
  }
  return true;
}

}  // namespace mocap
