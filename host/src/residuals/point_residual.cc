#include "mocap/residuals/point_residual.h"

#include <ceres/ceres.h>

#include <cmath>
#include <memory>

namespace mocap {

PointResidual::PointResidual(KinematicsCache* fk, const Site& site, const Eigen::Vector3d& target,
                             double weight)
    : fk_(fk), site_(site), target_(target), sqrt_weight_(std::sqrt(weight)) {
  set_num_residuals(3);
  *mutable_parameter_block_sizes() = ChainBlockSizes(fk->skeleton(), site.bone);
}

bool PointResidual::Evaluate(double const* const* parameters, double* residuals,
                             double** jacobians) const {
  const BodyPose& pose = fk_->Update(site_.bone, parameters);
  const Eigen::Vector3d x = pose.position[site_.bone] + pose.rotation[site_.bone] * site_.offset;
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = sqrt_weight_ * (x - target_);
  if (jacobians != nullptr) {
    const Eigen::Matrix3d m = sqrt_weight_ * Eigen::Matrix3d::Identity();
    PointJacobian<3>(fk_->skeleton(), pose, site_.bone, x, m, jacobians);
  }
  return true;
}

}  // namespace mocap
