#include "mocap/residuals/position_residual.h"

#include <cmath>

namespace mocap {

PositionResidual::PositionResidual(KinematicsCache* fk, const Camera* camera, const Site& site,
                                   const Eigen::Vector2d& detection, double confidence,
                                   double weight)
    : fk_(fk),
      camera_(camera),
      site_(site),
      detection_(detection),
      sqrt_weight_(std::sqrt(weight * confidence)) {
  set_num_residuals(2);
  *mutable_parameter_block_sizes() = ChainBlockSizes(fk->skeleton(), site.bone);
}

bool PositionResidual::Evaluate(double const* const* parameters, double* residuals,
                                double** jacobians) const {
  const BodyPose& pose = fk_->Update(site_.bone, parameters);
  const Eigen::Vector3d x = pose.position[site_.bone] + pose.rotation[site_.bone] * site_.offset;
  Eigen::Vector2d pixel;
  Eigen::Matrix<double, 2, 3> d_pixel;
  const bool want_jacobian = jacobians != nullptr;
  if (!camera_->Project(x, &pixel, want_jacobian ? &d_pixel : nullptr)) return false;
  Eigen::Map<Eigen::Vector2d> r(residuals);
  r = sqrt_weight_ * (pixel - detection_);
  if (want_jacobian) {
    const Eigen::Matrix<double, 2, 3> m = sqrt_weight_ * d_pixel;
    PointJacobian<2>(fk_->skeleton(), pose, site_.bone, x, m, jacobians);
  }
  return true;
}

}  // namespace mocap
