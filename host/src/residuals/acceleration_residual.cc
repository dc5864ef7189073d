#include "mocap/residuals/acceleration_residual.h"

#include <cmath>

namespace mocap {

AccelerationResidual::AccelerationResidual(KinematicsCache* fk, const ImuSite& site,
                                           const Eigen::Vector3d& x1, const Eigen::Vector3d& x0,
                                           double h1, double h2,
                                           const Eigen::Vector3d& measured_world, double weight)
    : fk_(fk),
      site_(site),
      x1_(x1),
      x0_(x0),
      measured_world_(measured_world),
      h1_(h1),
      h2_(h2),
      sqrt_weight_(std::sqrt(weight)) {
  set_num_residuals(3);
  *mutable_parameter_block_sizes() = ChainBlockSizes(fk->skeleton(), site.bone);
}

bool AccelerationResidual::Evaluate(double const* const* parameters, double* residuals,
                                    double** jacobians) const {
  const BodyPose& pose = fk_->Update(site_.bone, parameters);
  const Eigen::Vector3d x = pose.position[site_.bone] + pose.rotation[site_.bone] * site_.offset;
  const Eigen::Vector3d solved = 2.0 * ((x - x1_) / h2_ - (x1_ - x0_) / h1_) / (h1_ + h2_);
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = sqrt_weight_ * (solved - measured_world_);
  if (jacobians != nullptr) {
    const Eigen::Matrix3d m = position_scale() * Eigen::Matrix3d::Identity();
    PointJacobian<3>(fk_->skeleton(), pose, site_.bone, x, m, jacobians);
  }
  return true;
}

}  // namespace mocap
