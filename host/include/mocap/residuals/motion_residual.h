// E_M, motion term: E_A's acceleration cost for frames no accelerometer measures.
//
// Where an IMU measures acceleration, E_A compares it with the solved second difference;
// without one (video-only takes, --omit A) the per-frame solve has no temporal term and
// each frame follows its keypoints' noise. E_M costs the same second difference against a
// motion model instead: constant velocity, a(t1) = 0, so a point's acceleration is paid for
// as a measured one's error is, at a stated scale sigma_M (m/s^2): lambda_M = 1 / sigma_M^2.
//
// With E_A's non-uniform second difference over the current frame t and the previous t1,
// and the previous step's filtered velocity v standing in for x(t0) = x(t1) - v h1:
//   a_hat(t1) = 2 * [ (x(t) - x(t1)) / h2 - (x(t1) - x(t0)) / h1 ] / (h1 + h2)
//             = 2 * [ (x(t) - x(t1)) / h2 - v ] / (h1 + h2),     h1 = t1 - t0, h2 = t - t1
//   r = sqrt(lambda_M) * (a_hat(t1) - 0)                                (3, m/s^2)
// i.e. the distance of x(t) from the constant-velocity prediction x(t1) + v h2, scaled by
// 2 / (h2 (h1 + h2)) (1 / dt^2 for uniform steps). Only x(t) depends on theta:
//   dr/dtheta = sqrt(lambda_M) * 2 / (h2 (h1 + h2)) * dx/dtheta.
// The point x is any site on a bone (Site: bone + offset in the bone frame). The solver puts
// it on every joint centre, not on the IMU sites E_A uses: the frames E_M is for (video-only
// takes above all) have none, and the joint centres lie on every bone of each chain
// (Solver::motion_points_ says why those).
#ifndef MOCAP_RESIDUALS_MOTION_RESIDUAL_H_
#define MOCAP_RESIDUALS_MOTION_RESIDUAL_H_

#include <ceres/cost_function.h>

#include "mocap/kinematics.h"
#include "mocap/sites.h"

namespace mocap {

class MotionResidual : public ceres::CostFunction {
 public:
  // x1: the point's world position solved at t1 (metres); v: its filtered velocity over
  // the step [t1 - h1, t1] (m/s); h1, h2 in seconds (> 0); weight: lambda_M (s^4/m^2).
  MotionResidual(KinematicsCache* fk, const Site& site, const Eigen::Vector3d& x1,
                 const Eigen::Vector3d& v, double h1, double h2, double weight);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;
  // dr/dx: how the residual moves with the point's position (a scalar times the identity).
  double position_scale() const { return scale_; }

 private:
  KinematicsCache* fk_;
  Site site_;
  Eigen::Vector3d x1_, v_;
  double h2_, scale_;  // scale_ = sqrt(lambda_M) * 2 / (h2 (h1 + h2))
};

}  // namespace mocap

#endif  // MOCAP_RESIDUALS_MOTION_RESIDUAL_H_
