#include "frame_validation.h"

#include <cmath>

namespace mocap {

namespace {

// The detections of the frame's cameras: plausible keypoints above min_confidence.
void CleanKeypoints(const FrameObservations& frame, const Rig& rig, const KeypointLayout& layout,
                    const SolverOptions& options, CleanFrame* clean, InputCounts* counts) {
  std::vector<bool> camera_seen(rig.cameras.size(), false);
  for (const CameraObservation& obs : frame.cameras) {
    if (obs.camera < 0 || obs.camera >= static_cast<int>(rig.cameras.size()) ||
        camera_seen[obs.camera] || static_cast<int>(obs.keypoints.size()) != layout.size()) {
      ++counts->unknown_sources;
      continue;
    }
    camera_seen[obs.camera] = true;
    const Camera& cam = rig.cameras[obs.camera];
    for (int k = 0; k < layout.size(); ++k) {
      const Keypoint2D& kp = obs.keypoints[k];
      const bool finite =
          std::isfinite(kp.x) && std::isfinite(kp.y) && std::isfinite(kp.confidence);
      const bool plausible = finite && kp.confidence >= 0.0 && kp.confidence <= 1.0 + 1e-9 &&
                             kp.x > -cam.width && kp.x < 2.0 * cam.width && kp.y > -cam.height &&
                             kp.y < 2.0 * cam.height;
      if (!plausible) {
        ++counts->keypoints_invalid;
      } else if (kp.confidence <= options.min_confidence) {
        ++counts->keypoints_not_detected;
      } else {
        clean->detections.push_back({obs.camera, k, {kp.x, kp.y}, std::min(kp.confidence, 1.0)});
      }
    }
  }
}

// The IMUs' orientations and accelerations in the world frame, where they are valid.
void CleanImus(const FrameObservations& frame, const std::vector<ImuSite>& imus,
               const SolverOptions& options, CleanFrame* clean, InputCounts* counts) {
  std::vector<bool> imu_seen(imus.size(), false);
  for (const ImuObservation& obs : frame.imus) {
    if (obs.imu < 0 || obs.imu >= static_cast<int>(imus.size()) || imu_seen[obs.imu]) {
      ++counts->unknown_sources;
      continue;
    }
    imu_seen[obs.imu] = true;
    const double qn = obs.orientation.norm();
    const bool q_ok = obs.has_orientation && obs.orientation.coeffs().allFinite() &&
                      std::abs(qn - 1.0) <= options.max_quaternion_error;
    if (obs.has_orientation && !q_ok) ++counts->orientations_invalid;
    if (!q_ok) {
      if (obs.has_acceleration) ++counts->accelerations_invalid;  // cannot reach world frame
      continue;
    }
    const Eigen::Matrix3d world =
        imus[obs.imu].reference *
        Eigen::Quaterniond(obs.orientation.coeffs() / qn).toRotationMatrix();
    clean->imu_world[obs.imu] = world;
    if (obs.has_acceleration) {
      if (obs.acceleration.allFinite()) {
        clean->accel_world[obs.imu] = world * obs.acceleration - options.accel_at_rest;
      } else {
        ++counts->accelerations_invalid;
      }
    }
  }
}

}  // namespace

CleanFrame ValidateFrame(const FrameObservations& frame, const Rig& rig,
                         const KeypointLayout& layout, const std::vector<ImuSite>& imus,
                         const SolverOptions& options, InputCounts* counts) {
  CleanFrame clean;
  clean.timestamp = frame.timestamp;
  clean.imu_world.assign(imus.size(), std::nullopt);
  clean.accel_world.assign(imus.size(), std::nullopt);
  CleanKeypoints(frame, rig, layout, options, &clean, counts);
  CleanImus(frame, imus, options, &clean, counts);
  return clean;
}

}  // namespace mocap
