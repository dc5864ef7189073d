// E_R, orientation term (slide "Orientation terms").
//
//   r = sqrt(lambda_R) * Log( R_meas^T * G_b(theta) * R_m )          (3, radians)
//   E_R = rho_R(|r|^2),  R_meas = R_ig * R_i (measured sensor orientation in world)
//
// r is the rotation taking the measured sensor frame to the solved one, in the sensor
// frame. With the world-left perturbation G_b <- Exp(dphi) G_b (kinematics.h):
//   R_meas^T Exp(dphi) G_b R_m = (R_meas^T G_b R_m) Exp((G_b R_m)^T dphi)
// so dr/dphi = sqrt(lambda_R) * InverseRightJacobian(r0) * (G_b R_m)^T, r0 the unscaled r.
#ifndef MOCAP_RESIDUALS_ORIENTATION_RESIDUAL_H_
#define MOCAP_RESIDUALS_ORIENTATION_RESIDUAL_H_

#include <ceres/cost_function.h>

#include "mocap/kinematics.h"
#include "mocap/sites.h"

namespace mocap {

class OrientationResidual : public ceres::CostFunction {
 public:
  // measured_world: R_ig * R_i. weight: lambda_R (1/rad^2).
  OrientationResidual(KinematicsCache* fk, const ImuSite& site,
                      const Eigen::Matrix3d& measured_world, double weight);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  KinematicsCache* fk_;
  ImuSite site_;
  Eigen::Matrix3d measured_world_;
  double sqrt_weight_;
};

}  // namespace mocap

#endif  // MOCAP_RESIDUALS_ORIENTATION_RESIDUAL_H_
