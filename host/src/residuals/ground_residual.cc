#include "mocap/residuals/ground_residual.h"

#include <cmath>

namespace mocap {

GroundResidual::GroundResidual(KinematicsCache* fk, const Site& site, double floor, double weight)
    : fk_(fk), site_(site), floor_(floor), sqrt_weight_(std::sqrt(weight)) {
  set_num_residuals(1);
  *mutable_parameter_block_sizes() = ChainBlockSizes(fk->skeleton(), site.bone);
}

bool GroundResidual::Evaluate(double const* const* parameters, double* residuals,
                              double** jacobians) const {
  const BodyPose& pose = fk_->Update(site_.bone, parameters);
  const Eigen::Vector3d x = pose.position[site_.bone] + pose.rotation[site_.bone] * site_.offset;
  residuals[0] = sqrt_weight_ * (x.z() - floor_);
  if (jacobians != nullptr) {
    const Eigen::Matrix<double, 1, 3> m(0.0, 0.0, sqrt_weight_);
    PointJacobian<1>(fk_->skeleton(), pose, site_.bone, x, m, jacobians);
  }
  return true;
}

}  // namespace mocap
