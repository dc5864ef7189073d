// A 3D point term (not one of the paper's five): a site should sit at a target point.
//
//   r = sqrt(lambda) * (x_s(theta) - target)                         (3, metres)
//
// x_s = p_b + G_b s is the site in world. Used to fit the skeleton to triangulated
// keypoints (the video-only baseline of the evaluation) and to retarget motion onto a
// skeleton (FitToPoints, solver.h); dr/dtheta = sqrt(lambda) * dx/dtheta (kinematics.h).
#ifndef MOCAP_RESIDUALS_POINT_RESIDUAL_H_
#define MOCAP_RESIDUALS_POINT_RESIDUAL_H_

#include <ceres/cost_function.h>

#include "mocap/kinematics.h"
#include "mocap/sites.h"

namespace mocap {

class PointResidual : public ceres::CostFunction {
 public:
  // weight: lambda (1/m^2).
  PointResidual(KinematicsCache* fk, const Site& site, const Eigen::Vector3d& target,
                double weight);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  KinematicsCache* fk_;
  Site site_;
  Eigen::Vector3d target_;
  double sqrt_weight_;
};

}  // namespace mocap

#endif  // MOCAP_RESIDUALS_POINT_RESIDUAL_H_
