// E_P, position term (slide "Position terms").
//
//   r = sqrt(lambda_P * c) * (pi_c(x_p(theta)) - d)                    (2, pixels)
//   E_P = rho_P(|r|^2) = rho_P(lambda_P c |t_hat - t|^2),  rho_P(s) = log(1 + s) (Cauchy)
//
// x_p = p_b + G_b s_p is the keypoint site in world, pi_c the camera projection with
// distortion (camera.h), d the detection in pixels, c its confidence in (0, 1].
// dr/dtheta = sqrt(lambda_P c) * dpi/dx * dx/dtheta (kinematics.h).
// The residual fails (returns false) when the site is behind the camera, so Ceres
// rejects that step; the solver drops such observations before it starts.
#ifndef MOCAP_RESIDUALS_POSITION_RESIDUAL_H_
#define MOCAP_RESIDUALS_POSITION_RESIDUAL_H_

#include <ceres/cost_function.h>

#include "mocap/camera.h"
#include "mocap/kinematics.h"
#include "mocap/sites.h"

namespace mocap {

class PositionResidual : public ceres::CostFunction {
 public:
  // weight: lambda_P (1/px^2); confidence: c.
  PositionResidual(KinematicsCache* fk, const Camera* camera, const Site& site,
                   const Eigen::Vector2d& detection, double confidence, double weight);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  KinematicsCache* fk_;
  const Camera* camera_;
  Site site_;
  Eigen::Vector2d detection_;
  double sqrt_weight_;
};

}  // namespace mocap

#endif  // MOCAP_RESIDUALS_POSITION_RESIDUAL_H_
