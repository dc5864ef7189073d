// What the solver carries from frame to frame: the warm start predicted from the last two
// solved frames, the IMU sites' positions and velocities that the acceleration term (E_A)
// differentiates, and the joint centres' that the motion term (E_M) does.
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

namespace {

using Velocities = std::vector<std::optional<Eigen::Vector3d>>;

// The points' velocities at t (MotionState), from their positions now and at t1 (`before`),
// their velocities v and measured accelerations a at t1 (none for E_M's points); h1, h2 the
// steps before and after t1.
Velocities Filtered(const std::vector<Eigen::Vector3d>& now,
                    const std::vector<Eigen::Vector3d>& before, const Velocities& v,
                    const Velocities* a, double h1, double h2, double gain, bool reacquired) {
  Velocities next(now.size());
  for (size_t i = 0; i < now.size(); ++i) {
    const Eigen::Vector3d raw = (now[i] - before[i]) / h2;
    if (!v[i]) {
      if (!reacquired) next[i] = raw;  // a jump is no velocity
      continue;
    }
    Eigen::Vector3d predicted = *v[i];
    if (a != nullptr && (*a)[i]) predicted += *(*a)[i] * 0.5 * (h1 + h2);
    next[i] = predicted + gain * (raw - predicted);
  }
  return next;
}

std::vector<Eigen::Vector3d> Positions(const BodyPose& pose, const std::vector<Site>& sites) {
  std::vector<Eigen::Vector3d> x;
  for (const Site& s : sites) x.push_back(pose.position[s.bone] + pose.rotation[s.bone] * s.offset);
  return x;
}

}  // namespace

void Solver::Remember(const CleanFrame& frame, const BodyPose& pose, bool position_constrained,
                      Continuity continuity) {
  // A restart's jump is no motion: the prediction starts again from this frame.
  if (continuity == Continuity::kRestarted) {
    history_.clear();
  } else if (history_.size() == 2) {
    history_.erase(history_.begin());
  }
  history_.push_back({frame.timestamp, theta_, position_constrained});

  MotionState next;
  next.timestamp = frame.timestamp;
  next.accel = frame.accel_world;
  next.velocity.assign(imus_.size(), std::nullopt);
  next.point_velocity.assign(motion_points_.size(), std::nullopt);
  for (const ImuSite& s : imus_) {
    next.position.push_back(pose.position[s.bone] + pose.rotation[s.bone] * s.offset);
  }
  next.point_position = Positions(pose, motion_points_);
  const bool reacquired = continuity == Continuity::kReacquired;
  const double h2 = motion_ ? frame.timestamp - motion_->timestamp : 0.0;
  if (continuity != Continuity::kRestarted && h2 > 0.0 && h2 <= options_.max_history_gap) {
    next.step = h2;
    // A re-acquisition jump is drift since the last keypoints (none: no velocity evidence).
    const double drift_gain = last_fix_ ? h2 / (frame.timestamp - *last_fix_) : 0.0;
    const double h1 = motion_->step;
    next.velocity = Filtered(next.position, motion_->position, motion_->velocity, &motion_->accel,
                             h1, h2, reacquired ? drift_gain : options_.velocity_gain, reacquired);
    next.point_velocity =
        Filtered(next.point_position, motion_->point_position, motion_->point_velocity, nullptr, h1,
                 h2, reacquired ? drift_gain : options_.motion_velocity_gain, reacquired);
  }
  motion_ = std::move(next);
  if (position_constrained) last_fix_ = frame.timestamp;
}

double Solver::MotionInformation(double timestamp, const TermOptions& motion) const {
  const double h1 = motion_->step, h2 = timestamp - motion_->timestamp;
  const double per_unit_weight = 4.0 / (h2 * h2 * (h1 + h2) * (h1 + h2));  // (2 / (h2 (h1 + h2)))^2
  int accelerations = 0, points = 0;
  for (size_t i = 0; i < imus_.size(); ++i) {
    accelerations += !slips_.distrusted(static_cast<int>(i)) && motion_->velocity[i].has_value() &&
                     motion_->accel[i].has_value();
  }
  if (accelerations > 0 && options_.acceleration.enabled)
    return accelerations * options_.acceleration.weight * per_unit_weight;
  for (const auto& v : motion_->point_velocity) points += v.has_value();
  return motion.enabled ? points * motion.weight * per_unit_weight : 0.0;
}

TermOptions Solver::MotionTerm(bool oriented) const {
  TermOptions motion = options_.motion;
  if (!oriented) motion.weight *= options_.video_only_motion_weight_scale;
  return motion;
}

void Solver::AddMotionTerms(double timestamp, const TermOptions& term,
                            FrameProblem* problem) const {
  if (!term.enabled || !(term.weight > 0.0) || problem->count(kAccelerationTerm) > 0) return;
  for (size_t i = 0; i < motion_points_.size(); ++i) {
    if (!motion_->point_velocity[i]) continue;
    problem->AddMotionTerm(motion_points_[i], motion_->point_position[i],
                           *motion_->point_velocity[i], motion_->step,
                           timestamp - motion_->timestamp, term);
  }
}

void Solver::ChooseMotionPoints() {
  motion_points_.clear();
  for (int b = 0; b < skeleton_.num_bones(); ++b) {
    if (b == 0 || skeleton_.bone(b).offset.norm() > 0.0) motion_points_.push_back({b, {0, 0, 0}});
  }
}

}  // namespace mocap
