// E_A, acceleration term (slide "Acceleration terms").
//
// Solved acceleration of the IMU site at the previous frame, by the second finite
// difference over the current frame t and the two previous solved frames (t1, t0).
// For uniform steps this is the slide's (x(t) - 2 x(t1) + x(t0)) / dt^2; for jittered
// timestamps the non-uniform form
//   a_hat(t1) = 2 * [ (x(t) - x(t1)) / h2 - (x(t1) - x(t0)) / h1 ] / (h1 + h2),
//   h1 = t1 - t0, h2 = t - t1.
// Measured acceleration in world, gravity removed (the slide's formula):
//   a(t1) = R_ig * R_i(t1) * a_i(t1) - a_g
// a_i is the raw accelerometer reading in the sensor frame (m/s^2, gravity included)
// and a_g what a stationary accelerometer reads, in world (+9.81 m/s^2 along up).
//   r = sqrt(lambda_A) * (a_hat(t1) - a(t1))                           (3, m/s^2)
// Only x(t) depends on theta: dr/dtheta = sqrt(lambda_A) * 2 / (h2 (h1 + h2)) * dx/dtheta.
#ifndef MOCAP_RESIDUALS_ACCELERATION_RESIDUAL_H_
#define MOCAP_RESIDUALS_ACCELERATION_RESIDUAL_H_

#include <ceres/cost_function.h>

#include "mocap/kinematics.h"
#include "mocap/sites.h"

namespace mocap {

class AccelerationResidual : public ceres::CostFunction {
 public:
  // x1, x0: world site positions solved at t1 and t0 (metres); h1, h2 in seconds (> 0);
  // measured_world: a(t1) as above; weight: lambda_A (s^4/m^2).
  AccelerationResidual(KinematicsCache* fk, const ImuSite& site, const Eigen::Vector3d& x1,
                       const Eigen::Vector3d& x0, double h1, double h2,
                       const Eigen::Vector3d& measured_world, double weight);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;
  // dr/dx: how the residual moves with the site's position (a scalar times the identity).
  double position_scale() const { return sqrt_weight_ * 2.0 / (h2_ * (h1_ + h2_)); }

 private:
  KinematicsCache* fk_;
  ImuSite site_;
  Eigen::Vector3d x1_, x0_, measured_world_;
  double h1_, h2_, sqrt_weight_;
};

}  // namespace mocap

#endif  // MOCAP_RESIDUALS_ACCELERATION_RESIDUAL_H_
