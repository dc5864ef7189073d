// E_G, ground contact (not one of the paper's terms): the body's lowest foot contact point
// stands on the floor.
//
//   r = sqrt(lambda_G) * (e_z^T x_c(theta) - z_floor)                  (1, metres)
//   E_G = rho_G(|r|^2),  rho_G Cauchy: rho(s) = log(1 + s)
//
// x_c = p_b + G_b s_c is the contact site c in world (ground.h: heel, ball and toe tip of each
// foot), chosen by the solver as the lowest of them at the frame's warm start and held for
// the solve, z_floor the floor's height (SolverOptions::floor_height), lambda_G = 1 / sigma_G^2
// with sigma_G the height a stance foot's contact point varies by (the sites sit on an
// idealised sole). dr/dtheta = sqrt(lambda_G) * e_z^T dx/dtheta (kinematics.h PointJacobian).
//
// Why: with one camera, depth along its rays is observed only through the body's apparent
// size; a depth error moves the feet along their rays, so up or down unless the camera is at
// their height, and the floor pins it. Why robust: in a jump, a run's flight phase or a kick
// from the ground the lowest point is centimetres to decimetres up; Cauchy's pull, largest at
// sigma_G (1 / sigma_G) and falling as 2 / h beyond, then costs little and pulls little.
#ifndef MOCAP_RESIDUALS_GROUND_RESIDUAL_H_
#define MOCAP_RESIDUALS_GROUND_RESIDUAL_H_

#include <ceres/cost_function.h>

#include "mocap/kinematics.h"
#include "mocap/sites.h"

namespace mocap {

class GroundResidual : public ceres::CostFunction {
 public:
  // floor: world z (metres); weight: lambda_G (1/m^2).
  GroundResidual(KinematicsCache* fk, const Site& site, double floor, double weight);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  KinematicsCache* fk_;
  Site site_;
  double floor_, sqrt_weight_;
};

}  // namespace mocap

#endif  // MOCAP_RESIDUALS_GROUND_RESIDUAL_H_
