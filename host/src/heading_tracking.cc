// The solver's heading tracking: each IMU's heading (its reference frame's rotation about
// the vertical, which magnetometers let drift indoors) corrected slowly towards what the
// video-constrained pose says, and applied to the readings before each solve
// (docs/calibration.md).
#include <algorithm>
#include <cmath>

#include "frame_problem.h"
#include "frame_validation.h"
#include "mocap/kinematics.h"
#include "mocap/solver.h"

namespace mocap {

void Solver::TrackHeadings(const CleanFrame& frame, const BodyPose& pose) {
  const double dt = last_heading_update_ ? std::min(frame.timestamp - *last_heading_update_,
                                                    options_.max_history_gap)
                                         : 0.0;
  last_heading_update_ = frame.timestamp;
  if (options_.heading_time_constant <= 0.0 || dt <= 0.0) return;
  const double gain = std::min(1.0, dt / options_.heading_time_constant);
  for (size_t i = 0; i < imus_.size(); ++i) {
    if (!frame.imu_world[i]) continue;
    // The world-frame turn from the measured sensor orientation to the solved one; its
    // twist about z is the heading's error.
    const Eigen::Quaterniond q(pose.rotation[imus_[i].bone] * imus_[i].mount *
                               frame.imu_world[i]->transpose());
    double yaw = 2.0 * std::atan2(q.z(), q.w());
    if (yaw > M_PI) yaw -= 2.0 * M_PI;
    if (yaw < -M_PI) yaw += 2.0 * M_PI;
    if (options_.heading_baseline_s > 0.0) {
      HeadingBaseline& b = heading_baselines_[i];
      if (b.seconds < options_.heading_baseline_s) {  // still learning what "no drift" looks like
        b.seconds += dt;
        b.yaw_integral += yaw * dt;
        continue;
      }
      yaw -= b.yaw_integral / b.seconds;
    }
    yaw = std::clamp(yaw, -options_.max_heading_step, options_.max_heading_step);
    headings_[i] = std::remainder(headings_[i] + gain * yaw, 2.0 * M_PI);
  }
}

void Solver::TurnByHeadings(CleanFrame* clean) const {
  for (size_t i = 0; i < imus_.size(); ++i) {
    if (headings_[i] == 0.0 || !clean->imu_world[i]) continue;
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(headings_[i], Eigen::Vector3d::UnitZ()).matrix();
    clean->imu_world[i] = turn * *clean->imu_world[i];
    if (clean->accel_world[i]) {
      const Eigen::Vector3d& g = options_.accel_at_rest;
      clean->accel_world[i] = turn * (*clean->accel_world[i] + g) - g;
    }
  }
}

}  // namespace mocap
