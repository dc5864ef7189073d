#include "mocap/residuals/motion_residual.h"

#include <cmath>

namespace mocap {

MotionResidual::MotionResidual(KinematicsCache* fk, const Site& site, const Eigen::Vector3d& x1,
                               const Eigen::Vector3d& v, double h1, double h2, double weight)
    : fk_(fk),
      site_(site),
      x1_(x1),
      v_(v),
      h2_(h2),
      scale_(std::sqrt(weight) * 2.0 / (h2 * (h1 + h2))) {
  set_num_residuals(3);
  *mutable_parameter_block_sizes() = ChainBlockSizes(fk->skeleton(), site.bone);
}

bool MotionResidual::Evaluate(double const* const* parameters, double* residuals,
                              double** jacobians) const {
  const BodyPose& pose = fk_->Update(site_.bone, parameters);
  const Eigen::Vector3d x = pose.position[site_.bone] + pose.rotation[site_.bone] * site_.offset;
  // scale * (x - x1 - v h2) = sqrt(lambda) * 2 ((x - x1) / h2 - v) / (h1 + h2)
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = scale_ * (x - x1_ - v_ * h2_);
  if (jacobians != nullptr) {
    const Eigen::Matrix3d m = scale_ * Eigen::Matrix3d::Identity();
    PointJacobian<3>(fk_->skeleton(), pose, site_.bone, x, m, jacobians);
  }
  return true;
}

}  // namespace mocap
