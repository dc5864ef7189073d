// The passes of one frame's solve: a coarse pass when (re)initialising, the fine pass, and,
// when the keypoints cannot reach its solution, a re-acquisition from the warm start and a
// re-initialisation from the frame's own observations.
#include <cmath>
#include <limits>

#include "frame_validation.h"
#include "mocap/initialisation.h"
#include "mocap/solver.h"

namespace mocap {
namespace {

// Position loss scale multiplier of the coarse pass: a nearly quadratic loss pulls far-off
// limbs in, where the Cauchy loss would treat their large errors as outliers.
constexpr double kCoarseLossBoost = 1e4;

// A recovery (re-acquisition, re-initialisation) replaces the solution when it at least
// halves its mean keypoint cost. Pulled off by the motion terms, a pose scores 4-8 and its
// recovery ~1.1; one frame's odd keypoints (a detector's left-right swap in a single view)
// score just past max_keypoint_cost before and after, and a "recovery" fitting them was a
// metre off along the camera's rays (131_01, one camera): the tracked pose is kept there.
constexpr double kRecoveryGain = 0.5;

double MeanKeypointCost(const SolveResult& r) {
  return r.counts.keypoints_used > 0 ? r.costs.position / r.counts.keypoints_used
                                     : std::numeric_limits<double>::infinity();
}

bool Better(const SolveResult& candidate, const SolveResult& current) {
  if (candidate.counts.keypoints_used == 0) return false;
  return current.counts.keypoints_used == 0 ||
         MeanKeypointCost(candidate) <= kRecoveryGain * MeanKeypointCost(current);
}

// The cost under `t`'s loss with its scale times `scale` of a residual that costs `cost` under
// `t`'s loss: max_keypoint_cost is set in the plain loss's units, and a frame no IMU orients
// is solved with a wider loss (video_only_position_loss_scale), where a residual costs more.
double CostAtScale(const TermOptions& t, double cost, double scale) {
  const double b = t.loss_scale * t.loss_scale, a = b * scale * scale;
  double s = cost;  // the squared weighted residual of that cost
  switch (t.loss) {
    case LossType::kTrivial:
      return cost;
    case LossType::kCauchy:
      s = b * std::expm1(cost / b);
      return a * std::log1p(s / a);
    case LossType::kHuber:
      s = cost <= b ? cost : (cost + b) * (cost + b) / (4.0 * b);
      return s <= a ? s : 2.0 * std::sqrt(a * s) - a;
  }
  return cost;
}

}  // namespace

bool Solver::OrientationObserved(const CleanFrame& frame) const {
  if (!options_.orientation.enabled || !(options_.orientation.weight > 0.0)) return false;
  for (size_t i = 0; i < imus_.size(); ++i) {
    if (frame.imu_world[i] && !slips_.distrusted(static_cast<int>(i))) return true;
  }
  return false;
}

bool Solver::InLossTail(const SolveResult& r, const CleanFrame& frame) const {
  const double scale = OrientationObserved(frame) ? 1.0 : options_.video_only_position_loss_scale;
  return r.counts.keypoints_used > 0 &&
         MeanKeypointCost(r) > CostAtScale(options_.position, options_.max_keypoint_cost, scale);
}

bool Solver::CoarsePass(const CleanFrame& clean, int iterations, Eigen::VectorXd* x,
                        SolveResult* result) const {
  SolveResult coarse = *result;
  const bool ok = Optimise(clean, iterations, kCoarseLossBoost, false, x, &coarse);
  if (!ok) result->message = coarse.message;
  return ok;
}

bool Solver::SolvePasses(const CleanFrame& clean, double timestamp, bool initialising,
                         bool reacquiring, Eigen::VectorXd* x, SolveResult* result,
                         Continuity* continuity) const {
  // A new calibration moves the sensors' terms far from the warm start: the frame is solved
  // as a first frame is, from the warm start.
  const bool settling = initialising || calibration_changed_;
  const int iterations = settling ? options_.max_initial_iterations : options_.max_iterations;
  if ((settling || reacquiring) && !CoarsePass(clean, iterations, x, result)) {
    result->status = SolveStatus::kFailed;
    return false;
  }
  const Eigen::VectorXd warm_start = *x;
  const SolveResult before_fine_pass = *result;
  if (!Optimise(clean, iterations, 1.0, AccelerationUsable(timestamp, reacquiring), x, result))
    return false;
  *continuity = reacquiring ? Continuity::kReacquired : Continuity::kContinuous;
  if (initialising) return true;
  // The tracked pose lost the keypoints (they sit in the loss's tail, outvoted by the motion
  // terms): re-acquire it from the keypoints, and forget the velocities that carried it off.
  if (!reacquiring && InLossTail(*result, clean)) {
    Recover(clean, warm_start, iterations, before_fine_pass, kLostAndReacquired, x, result,
            continuity);
  }
  // Still out of the keypoints' reach (every one behind its camera: the pose ran away along
  // a camera's rays; or in the loss's tail after a re-acquisition): a pose the keypoints cannot
  // pull back is not held, the frame is solved as a first frame is, from its own observations.
  const bool behind =
      result->counts.keypoints_used == 0 && result->counts.keypoints_behind_camera > 0;
  if (behind || InLossTail(*result, clean)) {
    const Eigen::VectorXd start =
        EstimateInitialPose(skeleton_, rig_, layout_, imus_, clean.detections, clean.imu_world)
            .theta;
    Recover(clean, start, options_.max_initial_iterations, before_fine_pass, kReinitialised, x,
            result, continuity);
  }
  return true;
}

void Solver::Recover(const CleanFrame& clean, const Eigen::VectorXd& start, int iterations,
                     const SolveResult& before, QualityFlag flag, Eigen::VectorXd* x,
                     SolveResult* result, Continuity* continuity) const {
  Eigen::VectorXd candidate = start;
  SolveResult again = before;
  if (!CoarsePass(clean, iterations, &candidate, &again) ||
      !Optimise(clean, iterations, 1.0, false, &candidate, &again) || !Better(again, *result)) {
    return;  // no better: the solution stays
  }
  *x = candidate;
  *result = again;
  result->flags |= flag;
  *continuity = Continuity::kRestarted;
}

}  // namespace mocap
