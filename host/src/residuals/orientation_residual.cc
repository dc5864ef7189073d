#include "mocap/residuals/orientation_residual.h"

#include <cmath>

#include "mocap/so3.h"

namespace mocap {

OrientationResidual::OrientationResidual(KinematicsCache* fk, const ImuSite& site,
                                         const Eigen::Matrix3d& measured_world, double weight)
    : fk_(fk), site_(site), measured_world_(measured_world), sqrt_weight_(std::sqrt(weight)) {
  set_num_residuals(3);
  *mutable_parameter_block_sizes() = ChainBlockSizes(fk->skeleton(), site.bone);
}

bool OrientationResidual::Evaluate(double const* const* parameters, double* residuals,
                                   double** jacobians) const {
  const BodyPose& pose = fk_->Update(site_.bone, parameters);
  const Eigen::Matrix3d sensor_world = pose.rotation[site_.bone] * site_.mount;
  const Eigen::Vector3d r0 = Log(measured_world_.transpose() * sensor_world);
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = sqrt_weight_ * r0;
  if (jacobians != nullptr) {
    const Eigen::Matrix3d m = sqrt_weight_ * InverseRightJacobian(r0) * sensor_world.transpose();
    RotationJacobian<3>(fk_->skeleton(), pose, site_.bone, m, jacobians);
  }
  return true;
}

}  // namespace mocap
