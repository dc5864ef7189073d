// Which IMUs the keypoints contradict: a sensor that slipped on its segment, failed, or was
// mounted other than its calibration says.
//
// The solve lets each sensor's orientation win over the pose prior (a dancer's ankle far
// outside the training motion is still the sensor's), so a sensor that is wrong turns its
// bone away from the keypoints that bone carries. After each solve the monitor scores every
// IMU by the mean robust reprojection cost, log(1 + w e^2) in the position term's units, of
// its own keypoints: those that move with its bone's rotation and not with a lower sensor's
// bone (the forearm's: wrist and hand; the shin's: ankle, not the foot's heel and toe when
// the foot has a sensor). A tracked pose scores ~1-2, a bone turned 45-90 degrees away from its
// keypoints 4.2-6 (measured on the evaluation clips). When the median over slip_window_s exceeds
// slip_keypoint_cost, the sensor is distrusted: left out of E_R and E_A, reported, and its
// bone solved from the keypoints and the prior. Of the flagged sensors of one chain the
// upstream one is distrusted (a slipped shin turns the foot's keypoints away too) and the
// chain below it starts its evidence again. A distrusted sensor is trusted again once its
// orientation has agreed with the solved bone within slip_readmit_deg for slip_readmit_s.
// A sensor whose bone no keypoint observes (one camera that does not see it, COCO-17 feet)
// has no evidence and stays trusted.
#ifndef MOCAP_SLIP_MONITOR_H_
#define MOCAP_SLIP_MONITOR_H_

#include <Eigen/Core>
#include <deque>
#include <optional>
#include <vector>

#include "mocap/camera.h"
#include "mocap/initialisation.h"
#include "mocap/kinematics.h"
#include "mocap/sites.h"
#include "mocap/skeleton.h"
#include "mocap/solver_options.h"

namespace mocap {

class SlipMonitor {
 public:
  SlipMonitor() = default;
  SlipMonitor(const Skeleton& skeleton, const KeypointLayout& layout,
              const std::vector<ImuSite>& imus);

  // Whether IMU i is left out of the solve.
  bool distrusted(int i) const { return sensors_[i].distrusted; }
  int size() const { return static_cast<int>(sensors_.size()); }
  // The layout's keypoints that are IMU i's evidence.
  const std::vector<int>& own_keypoints(int i) const { return sensors_[i].keypoints; }

  // After the solve of a frame at `timestamp` that tracked the keypoints (not a first frame or
  // a re-acquisition: their residuals say nothing of one sensor): `pose` the solution,
  // `detections` the frame's keypoints, `imu_world` each IMU's measured world orientation
  // (absent when it gave none).
  void Update(double timestamp, const SolverOptions& options, const Rig& rig,
              const KeypointLayout& layout, const BodyPose& pose,
              const std::vector<Detection>& detections,
              const std::vector<std::optional<Eigen::Matrix3d>>& imu_world);

 private:
  struct Sensor {
    int bone = 0;
    Eigen::Matrix3d mount = Eigen::Matrix3d::Identity();
    std::vector<int> keypoints;                   // its own
    std::vector<int> below;                       // sensors further down its chain
    std::deque<std::pair<double, double>> costs;  // (time, mean cost of its own keypoints)
    bool distrusted = false;
    std::optional<double> agreeing_since;  // distrusted: first of the frames agreeing since
  };
  // The mean cost of each sensor's own keypoints in this frame (NaN: none seen).
  std::vector<double> OwnCosts(const SolverOptions& options, const Rig& rig,
                               const KeypointLayout& layout, const BodyPose& pose,
                               const std::vector<Detection>& detections) const;
  // Median over the window when it spans enough of slip_window_s, else NaN.
  static double WindowMedian(const Sensor& s, double window_s);
  void Readmit(double timestamp, const SolverOptions& options, const BodyPose& pose,
               const std::vector<std::optional<Eigen::Matrix3d>>& imu_world);

  std::vector<Sensor> sensors_;
  std::vector<int> upstream_first_;  // sensor indices, ancestors before descendants
};

}  // namespace mocap

#endif  // MOCAP_SLIP_MONITOR_H_
