// The prediction shift (not one of the paper's terms): how far the motion terms' prediction
// of the body's position may be off.
//
// E_A and E_M (acceleration_residual.h, motion_residual.h) cost each point's second
// difference over the current frame, the previous solution x(t1) and its velocity v: in
// effect a prediction x(t1) + v h2 (+ the measured acceleration's share) with the
// acceleration's uncertainty alone, sigma_a h2^2 / 2 (a few millimetres), as if x(t1) and v
// were exact. Where the keypoints fix the body's position (two cameras or more) they are near
// enough. Along a direction the keypoints barely observe (the depth of a single camera: 80 cm
// there moves the keypoints by about their noise), x(t1) is as uncertain as that, and a
// prediction held to millimetres outweighs them: the keypoints correct a wrong velocity by a
// fraction of a millimetre per frame, and the body runs along the camera's rays for seconds.
//
// So the prediction of every motion point may shift together by delta (3, metres, world),
// one parameter block of the frame's problem: each motion residual becomes
//   r(theta, delta) = r(theta) - s delta,        s = dr/dx (the residual's position_scale)
// (delta moves the prediction x(t1) + v h2 as a change of x(t1) would), and delta costs
//   r_delta = U delta,   U^T U = Lambda = (H / kappa) (I + H / (r W)) + I / sigma_max^2,
// H the information of the frame's keypoints and ground contact on the root's position (their
// Gauss-Newton J^T J on it at the warm start, robust weights included), W = sum of s^2 the
// motion terms' own on it, kappa = SolverOptions::prediction_slack. Minimised over delta, the
// motion terms' common pull on the root is the series combination (W^-1 + Lambda^-1)^-1:
// along a direction where the keypoints give h = x W, W / (1 + kappa / (x (1 + x / r))).
//  - Barely observed (x << r; one camera's depth, x ~ 1e-3): Lambda ~ H / kappa, the Kalman
//    filter's prediction covariance taken as kappa times the frame's own measurement
//    covariance (a steady-state filter has it so, kappa = alpha / (1 - alpha) for its position
//    gain alpha): the root follows the keypoints' innovation by kappa / (1 + kappa) per frame
//    instead of dead-reckoning away.
//  - Observed (x >> r): the pull tends to W (within kappa r / x^2), where E_A's weight and
//    velocity filter were tuned (eight cameras, x ~ 0.2-0.4: within 6-24%, and the results
//    are those without the shift). Two cameras (x ~ 0.03-0.1) and one camera's other
//    directions (~0.07) are in between. A frame whose every direction would be loosened by
//    less than 10% is solved without delta (Solver::ShiftMatters).
// (x: geometric means over the frames of cmu-daz/10_02, the validation kick, by eigenvector of H.)
// sigma_max bounds the shift where the keypoints see nothing (a frame whose few keypoints
// leave a direction free).
#ifndef MOCAP_RESIDUALS_PREDICTION_SHIFT_H_
#define MOCAP_RESIDUALS_PREDICTION_SHIFT_H_

#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <memory>

namespace mocap {

// A motion residual (E_A or E_M) with its prediction shifted by delta: the inner residual's
// parameter blocks, then delta's (3).
class ShiftedPrediction : public ceres::CostFunction {
 public:
  // inner: the motion residual (owned); scale: its position_scale().
  ShiftedPrediction(std::unique_ptr<ceres::CostFunction> inner, double scale);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  std::unique_ptr<ceres::CostFunction> inner_;
  double scale_;
};

// r = U delta (3), U^T U = information (symmetric positive definite).
class PredictionShiftPrior : public ceres::CostFunction {
 public:
  explicit PredictionShiftPrior(const Eigen::Matrix3d& information);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  Eigen::Matrix3d u_;
};

}  // namespace mocap

#endif  // MOCAP_RESIDUALS_PREDICTION_SHIFT_H_
