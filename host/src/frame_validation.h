// Checking a frame's observations before a solve: every keypoint and IMU reading is used
// or counted once in InputCounts. Internal to the solver.
#ifndef MOCAP_SRC_FRAME_VALIDATION_H_
#define MOCAP_SRC_FRAME_VALIDATION_H_

#include <optional>
#include <vector>

#include "mocap/initialisation.h"
#include "mocap/solver.h"

namespace mocap {

// A frame's usable observations, in world terms.
struct CleanFrame {
  double timestamp = 0;
  std::vector<Detection> detections;  // finite, confidence above the threshold, plausible pixel
  std::vector<std::optional<Eigen::Matrix3d>> imu_world;    // R_ig R_i per IMU site
  std::vector<std::optional<Eigen::Vector3d>> accel_world;  // R_ig R_i a_i - a_g per IMU site
};

// Drops and counts: unknown or duplicate cameras and IMUs, keypoint lists of the wrong
// length, NaN / inf values, confidences outside [0, 1], pixels far outside the image,
// quaternions whose norm is off by more than options.max_quaternion_error (and the
// accelerations that then cannot be rotated to world).
CleanFrame ValidateFrame(const FrameObservations& frame, const Rig& rig,
                         const KeypointLayout& layout, const std::vector<ImuSite>& imus,
                         const SolverOptions& options, InputCounts* counts);

}  // namespace mocap

#endif  // MOCAP_SRC_FRAME_VALIDATION_H_
