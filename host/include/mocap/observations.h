// What the solver is given each frame, and what it gives back.
//
// Any subset of cameras and IMUs may appear in a frame; missing ones are simply absent.
// Quaternions: Eigen::Quaterniond, constructed (w, x, y, z), stored (x, y, z, w).
#ifndef MOCAP_OBSERVATIONS_H_
#define MOCAP_OBSERVATIONS_H_

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

namespace mocap {

struct Keypoint2D {
  double x = 0, y = 0;    // pixels, distorted image
  double confidence = 0;  // [0, 1]; 0 means "not detected"
};

struct CameraObservation {
  int camera = 0;                     // index into the rig
  std::vector<Keypoint2D> keypoints;  // in the layout's order, one per keypoint
};

struct ImuObservation {
  int imu = 0;                                 // index into the IMU sites
  Eigen::Quaterniond orientation{1, 0, 0, 0};  // R_i: sensor -> IMU reference frame
  Eigen::Vector3d acceleration{0, 0, 0};       // a_i: m/s^2, sensor frame, gravity included
  bool has_orientation = true;
  bool has_acceleration = true;
};

struct FrameObservations {
  double timestamp = 0;  // seconds on the shared timebase; must increase frame to frame
  std::vector<CameraObservation> cameras;
  std::vector<ImuObservation> imus;
};

enum class SolveStatus {
  kOk,              // solved from the warm start
  kInitialised,     // first frame (or after a reset): solved from an initial guess
  kNoObservations,  // nothing usable in the frame: the previous pose is held
  kRejectedFrame,   // timestamp not finite or not after the previous frame
  kFailed,          // the optimiser failed, or the pose is over 100 m from every camera
                    // (refused): the previous pose is held
};
const char* ToString(SolveStatus status);

// Quality flags (bit mask).
enum QualityFlag : uint32_t {
  kPositionUnconstrained = 1u << 0,    // no camera constrained the pose: global position drifts
  kIterationLimit = 1u << 1,           // stopped at the iteration limit, not by convergence
  kAccelerationUnavailable = 1u << 2,  // no acceleration history (first frames, after a gap)
  kLostAndReacquired = 1u << 3,        // the tracked pose had lost the keypoints: re-acquired
  // The keypoints could not reach the solved pose (every one behind its camera, or still in
  // the loss's tail after a re-acquisition): solved again from this frame's own initial pose.
  kReinitialised = 1u << 4,
};

// Per-term cost E = sum of rho(|r|^2) at the solution, as on the slide; motion is E_M, the
// acceleration cost of frames without E_A (residuals/motion_residual.h), ground E_G, the lowest
// foot contact point's height above the floor (residuals/ground_residual.h).
struct TermCosts {
  double orientation = 0, position = 0, acceleration = 0, pca_projection = 0, pca_deviation = 0;
  double motion = 0, ground = 0;
};

// What happened to the frame's inputs: every observation is used or counted once.
struct InputCounts {
  int keypoints_used = 0;
  int keypoints_not_detected = 0;   // confidence at or below the threshold
  int keypoints_invalid = 0;        // NaN / inf, confidence out of range, far outside the image
  int keypoints_behind_camera = 0;  // site behind the camera at the start of the solve
  int orientations_used = 0;
  int orientations_invalid = 0;  // NaN or not a unit quaternion
  // From a sensor the keypoints contradict (slip_monitor.h): left out, with its acceleration.
  int orientations_distrusted = 0;
  int accelerations_used = 0;
  int accelerations_invalid = 0;  // NaN / inf
  int unknown_sources = 0;        // camera or IMU index not in the rig / IMU set, or duplicate
};

// Where the time of one Levenberg-Marquardt solve went, milliseconds.
struct SolveTimings {
  double total = 0;                // the solve, all of it
  double linear_solver = 0;        // normal equations: J^T J and its Cholesky factorisation
  double jacobian_evaluation = 0;  // residuals and Jacobians
  double residual_evaluation = 0;  // residuals only (candidate steps)
};

struct SolveResult {
  SolveStatus status = SolveStatus::kNoObservations;
  Eigen::VectorXd theta;  // always finite
  double timestamp = 0;
  TermCosts costs;
  InputCounts counts;
  uint32_t flags = 0;
  int iterations = 0;
  double solve_time_ms = 0;  // wall time of Solve()
  SolveTimings timings;      // of the final pass
  std::string message;       // human-readable reason when status is not kOk
  // The IMU sites left out of this solve as the keypoints contradict them (slip_monitor.h).
  std::vector<int> imus_distrusted;
};

}  // namespace mocap

#endif  // MOCAP_OBSERVATIONS_H_
