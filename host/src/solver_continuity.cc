// What the solver carries from frame to frame: the warm start predicted from the last two
// solved frames, and the IMU sites' positions and velocities that the acceleration term
// (E_A) differentiates.
#include <cmath>

#include "frame_problem.h"
#include "frame_validation.h"
#include "mocap/so3.h"
#include "mocap/solver.h"

namespace mocap {

bool Solver::AccelerationUsable(double timestamp, bool reacquiring) const {
  if (!motion_ || reacquiring) return false;
  const double h2 = timestamp - motion_->timestamp;
  return h2 > 0.0 && h2 <= options_.max_history_gap;
}

bool Solver::PredictionUsable(double timestamp) const {
  if (history_.size() < 2) return false;
  const double h1 = history_[1].timestamp - history_[0].timestamp;
  const double h2 = timestamp - history_[1].timestamp;
  return h1 > 0.0 && h2 > 0.0 && h1 <= options_.max_history_gap && h2 <= options_.max_history_gap &&
         history_[0].position_constrained == history_[1].position_constrained;
}

Eigen::VectorXd Solver::WarmStart(double timestamp) const {
  if (!options_.predict_motion || warm_start_given_ || !PredictionUsable(timestamp)) return theta_;
  const SolvedFrame& a = history_[0];
  const SolvedFrame& b = history_[1];
  const double s = (timestamp - b.timestamp) / (b.timestamp - a.timestamp);
  Eigen::VectorXd x = theta_;
  x.head<3>() += s * (b.theta.head<3>() - a.theta.head<3>());
  for (int b_idx = 0; b_idx < skeleton_.num_bones(); ++b_idx) {
    const int i = Skeleton::RotationIndex(b_idx);
    const Eigen::Matrix3d ra = Exp(a.theta.segment<3>(i)), rb = Exp(b.theta.segment<3>(i));
    x.segment<3>(i) = Log(rb * Exp(s * Log(ra.transpose() * rb)));
  }
  return x;
}

void Solver::Remember(const CleanFrame& frame, const BodyPose& pose, bool position_constrained,
                      Continuity continuity) {
  if (history_.size() == 2) history_.erase(history_.begin());
  history_.push_back({frame.timestamp, theta_, position_constrained});

  MotionState next;
  next.timestamp = frame.timestamp;
  next.accel = frame.accel_world;
  next.velocity.assign(imus_.size(), std::nullopt);
  for (const ImuSite& s : imus_) {
    next.position.push_back(pose.position[s.bone] + pose.rotation[s.bone] * s.offset);
  }
  const bool reacquired = continuity == Continuity::kReacquired;
  const double h2 = motion_ ? frame.timestamp - motion_->timestamp : 0.0;
  if (continuity != Continuity::kRestarted && h2 > 0.0 && h2 <= options_.max_history_gap) {
    next.step = h2;
    // A re-acquisition jump is drift since the last keypoints (none: no velocity evidence).
    const double gain = !reacquired ? options_.velocity_gain
                        : last_fix_ ? h2 / (frame.timestamp - *last_fix_)
                                    : 0.0;
    for (size_t i = 0; i < imus_.size(); ++i) {
      const Eigen::Vector3d raw = (next.position[i] - motion_->position[i]) / h2;
      const std::optional<Eigen::Vector3d>& v = motion_->velocity[i];
      if (!v) {
        if (!reacquired) next.velocity[i] = raw;  // a jump is no velocity
        continue;
      }
      Eigen::Vector3d predicted = *v;
      if (motion_->accel[i]) predicted += *motion_->accel[i] * 0.5 * (motion_->step + h2);
      next.velocity[i] = predicted + gain * (raw - predicted);
    }
  }
  motion_ = std::move(next);
  if (position_constrained) last_fix_ = frame.timestamp;
}

}  // namespace mocap
