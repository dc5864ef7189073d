// The options of the per-frame solve (solver.h): plain structs with their defaults inline.
//
// Each struct names its fields once, in VisitFields: visit(name, &Struct::field) for every
// field, the name being the session file's key and the Python attribute. The session reader
// (daemon/options_json.h), the Python bindings and the field-list tests are derived from it,
// so a field added here and to VisitFields reaches all of them; src/options_test.cc fails
// when a field is left out of VisitFields.
#ifndef MOCAP_SOLVER_OPTIONS_H_
#define MOCAP_SOLVER_OPTIONS_H_

#include <Eigen/Core>
#include <limits>
#include <string>

namespace mocap {

enum class LossType { kTrivial, kCauchy, kHuber };

// One cost term: E = rho(weight * |e|^2), rho scaled by loss_scale (Cauchy: Ceres'
// CauchyLoss(a), rho(s) = a^2 log(1 + s/a^2), a = loss_scale). Units of weight are the inverse
// square of the term's.
struct TermOptions {
  bool enabled = true;
  double weight = 1.0;
  LossType loss = LossType::kTrivial;
  double loss_scale = 1.0;

  // One message per failing condition, each field prefixed with `name` ("position.").
  bool IsValid(const std::string& name, std::string* error) const;

  template <typename Visit>
  static void VisitFields(Visit&& visit) {
    visit("enabled", &TermOptions::enabled);
    visit("weight", &TermOptions::weight);
    visit("loss", &TermOptions::loss);
    visit("loss_scale", &TermOptions::loss_scale);
  }
};

struct SolverOptions {
  // Weights: 1 / (typical error)^2 of each measurement, so a typical error costs ~1.
  // E_R without a robust loss: a sensor wins over the prior on poses the prior never saw; one
  // the keypoints contradict is left out instead (slip_monitor.h).
  TermOptions orientation{true, 1.0 / (0.035 * 0.035), LossType::kTrivial, 4.0};  // 2 degrees
  TermOptions position{true, 1.0 / 25.0, LossType::kCauchy, 1.0};                 // 5 pixels
  // On frames no IMU orientation constrains (a video-only take; every sensor lost or left
  // out) the keypoints are all that orients the bones, and video noise is all E_M smooths:
  // E_P's loss scale is multiplied by video_only_position_loss_scale (with the Cauchy loss at
  // 5 px the prior outvoted what they said consistently: the real Balancing take's pelvis came
  // out 24 degrees off in yaw from the triangulated hips, the left hip 9 cm away) and E_M's
  // weight by video_only_motion_weight_scale (sigma 55 -> 32 m/s^2). 3 and 55/32 squared: that
  // take's distance 3.69 -> 2.88 cm and jitter 14.4 -> 13.9 m/s^2 (docs/results_real.md). Frames
  // with IMU orientations but no accelerations keep E_M at 55: stronger, a smooth synthetic motion
  // lagged by 2-4 mm.
  double video_only_position_loss_scale = 3.0;
  double video_only_motion_weight_scale = (55.0 * 55.0) / (32.0 * 32.0);
  // E_A compares the measured acceleration with the second difference of the solved
  // positions, whose previous velocity is filtered (velocity_gain): 18 m/s^2 and the gain
  // 0.3 were tuned on the validation clips (docs/results.md, "Tuning").
  TermOptions acceleration{true, 1.0 / (18.0 * 18.0), LossType::kCauchy, 1.0};
  TermOptions pca_projection{true, 1.0 / (0.15 * 0.15), LossType::kTrivial, 1.0};  // 0.15 rad
  // E_M (residuals/motion_residual.h): on frames without E_A (no IMU measures acceleration),
  // each joint centre's acceleration costs as a measured one's error does, against a
  // constant-velocity model, at 55 m/s^2 (32 on video-only frames, above; stronger smooths
  // more and lags more: docs/results_real.md, the Balancing take). Video noise makes per-frame
  // accelerations larger than the motion's own (that take: 49 m/s^2 solved, 8 in Pose2Sim's
  // filtered 3D), so no loss tells them apart by size; Cauchy bounds what a point pulls against
  // the keypoints, so a fast real motion (a walk's heel strike) is followed rather than lagged:
  // trivial, a simulated walk's video-only position error was 5.6 cm instead of 3.8 (mocap eval
  // --omit R A).
  TermOptions motion{true, 1.0 / (55.0 * 55.0), LossType::kCauchy, 1.0};
  // One standard deviation of the prior costs as much as a keypoint at its typical error;
  // weaker, the DOF the data leave free (toe, hand, clavicle twist) wander
  // (measured on the evaluation clips).
  TermOptions pca_deviation{true, 1.0, LossType::kTrivial, 1.0};
  // E_G (residuals/ground_residual.h): the lowest foot contact point on the floor, on frames
  // whose floor_height is known. 2 cm: the lowest contact site's spread about the floor on the
  // clips' frames (quartiles within 3 cm: an idealised sole on mocap whose feet dip and
  // float); Cauchy, so a jump's or a run's flight, decimetres up, costs and pulls little
  // (host/README.md, the per-frame solve).
  TermOptions ground{true, 1.0 / (0.02 * 0.02), LossType::kCauchy, 1.0};  // 2 cm
  // E_G on frames without keypoints (IMUs only): nothing else observes the root's height,
  // and the acceleration term's dead reckoning drifts (accelerometer bias, tilt error): the
  // body rose 28 cm in 4 s without cameras on a test clip, E_G's Cauchy giving up beyond a
  // few cm. There its loss scale is multiplied by this (25: quadratic to ~10 cm), which holds
  // the height. Its weight as well (stiffer) held a synthetic 0.3 m/s^2 bias better but
  // drifted more on the test clips (docs/results.md, "Cameras lost"); a stance foot held in
  // place was tried and left out too: the clips' feet slide 0.2 cm per frame on the floor.
  double ground_unobserved_scale = 25.0;
  // The floor's height (world z, metres), as FloorHeight (ground.h) defines it from poses: the
  // median of each pose's lowest foot contact site, so a sole's thickness is part of it. NaN:
  // unknown, and E_G is off (a session without a floor estimate solves as before E_G existed).
  double floor_height = std::numeric_limits<double>::quiet_NaN();

  Eigen::Vector3d accel_at_rest{0, 0, 9.80665};  // a_g: stationary accelerometer, world, m/s^2
  double min_confidence = 0.05;                  // detections at or below are "not detected"
  double max_quaternion_error = 1e-3;            // | |q| - 1 | above this: the reading is rejected
  double max_history_gap = 0.25;  // s: older solved frames do not feed E_A or prediction
  // E_A's previous velocity of each IMU site (see Solver::MotionState): 1 takes the
  // difference of the last two solutions, as the slide's second difference; below 1, a
  // complementary filter of that difference and the velocity integrated from the IMUs.
  double velocity_gain = 0.3;
  // The same filter for E_M's points (Solver::MotionState), whose prediction has no measured
  // acceleration: v <- v + motion_velocity_gain (raw - v). 0.3-1 score alike on the Balancing
  // take; 0.6 lags least on the simulated walk.
  double motion_velocity_gain = 0.6;
  // The motion terms' prediction (E_A's, E_M's) may shift by about sqrt(prediction_slack)
  // times the frame's own uncertainty of the root's position from its keypoints and ground
  // contact (residuals/prediction_shift.h): along a direction the keypoints barely observe
  // (one camera's depth) the root then follows them by slack / (1 + slack) of their pull per
  // frame instead of dead-reckoning away; where they observe it (two cameras or more)
  // nothing changes. 0: the prediction is exact (the paper's).
  double prediction_slack = 1.0;
  // Mean robust cost per keypoint (rho, in the position loss's units) above which the
  // tracked pose is taken to have lost the keypoints and is re-acquired from them; a
  // tracked pose scores ~1.1, one carried off by the motion terms 4-8
  // (measured on the evaluation clips). In the plain loss's units: on a frame solved with
  // video_only_position_loss_scale the limit is the cost of the same residual under that
  // loss (compared unmapped, every video-only frame of the Balancing take was re-acquired:
  // 1.5 ms a frame instead of 0.28).
  double max_keypoint_cost = 2.5;
  // Warm start from a constant-velocity prediction of the two previous solutions (on
  // SO(3) per joint) instead of the previous solution alone.
  bool predict_motion = true;
  // Heading tracking (0: off): each IMU's reference frame is turned about world z by a
  // heading correction psi_i that follows, with this time constant (s), the yaw between the
  // solved sensor orientation and the measured one on frames the keypoints constrain. Video
  // sees a segment's yaw (a limb's when it is not vertical, the pelvis' through the hips), so
  // a heading estimated from a short window, or drifting as magnetometers do indoors, is
  // pulled to what the cameras see; a yaw video does not see leaves psi_i where it is.
  double heading_time_constant = 0.0;
  double max_heading_step = 0.1;  // rad: a frame's yaw beyond this counts as this much
  // 0: the headings follow the yaw itself (headings fitted to this video, as the window
  // calibration's are). > 0: each IMU's mean yaw over its first heading_baseline_s seconds
  // of tracked frames is its baseline, and the heading follows changes from it: drift only,
  // for headings from elsewhere (a suit's calibration) whose video yaw the detector's
  // systematic keypoint offsets bias by a few degrees.
  double heading_baseline_s = 0.0;
  // Slipped or failed sensors (slip_monitor.h): a sensor whose own keypoints' mean robust
  // cost (position loss units) has a median above slip_keypoint_cost over slip_window_s is
  // left out of the solve (0: never), and trusted again once its orientation agrees with the
  // solved bone within slip_readmit_deg for slip_readmit_s. On the test clips with true
  // sensors the median peaks at 1.5-2.6, and at 4.4 once (an arm at the image's edge); a
  // forearm slipped 60 degrees scores 4.6-4.8, a shin slipped 90 degrees 6.0.
  double slip_keypoint_cost = 4.5;
  double slip_window_s = 0.5;
  double slip_readmit_deg = 15.0;
  double slip_readmit_s = 1.0;
  int max_iterations = 10;           // per warm-started frame
  int max_initial_iterations = 100;  // for the first frame
  // Relative cost change that ends a frame. Warm-started frames reach their accuracy in
  // 2-3 iterations; tighter tolerances add iterations, not accuracy (docs/performance.md).
  double function_tolerance = 1e-3;
  double gradient_tolerance = 1e-10;
  double parameter_tolerance = 1e-8;

  // True when every field is in range; else *error holds one message per failing
  // condition ("velocity_gain = 0 is out of range (must be in (0, 1])"), joined by "; ".
  bool IsValid(std::string* error) const;

  template <typename Visit>
  static void VisitFields(Visit&& visit) {
    visit("orientation", &SolverOptions::orientation);
    visit("position", &SolverOptions::position);
    visit("video_only_position_loss_scale", &SolverOptions::video_only_position_loss_scale);
    visit("video_only_motion_weight_scale", &SolverOptions::video_only_motion_weight_scale);
    visit("acceleration", &SolverOptions::acceleration);
    visit("pca_projection", &SolverOptions::pca_projection);
    visit("pca_deviation", &SolverOptions::pca_deviation);
    visit("motion", &SolverOptions::motion);
    visit("ground", &SolverOptions::ground);
    visit("ground_unobserved_scale", &SolverOptions::ground_unobserved_scale);
    visit("floor_height", &SolverOptions::floor_height);
    visit("accel_at_rest", &SolverOptions::accel_at_rest);
    visit("min_confidence", &SolverOptions::min_confidence);
    visit("max_quaternion_error", &SolverOptions::max_quaternion_error);
    visit("max_history_gap", &SolverOptions::max_history_gap);
    visit("velocity_gain", &SolverOptions::velocity_gain);
    visit("motion_velocity_gain", &SolverOptions::motion_velocity_gain);
    visit("prediction_slack", &SolverOptions::prediction_slack);
    visit("max_keypoint_cost", &SolverOptions::max_keypoint_cost);
    visit("predict_motion", &SolverOptions::predict_motion);
    visit("heading_time_constant", &SolverOptions::heading_time_constant);
    visit("max_heading_step", &SolverOptions::max_heading_step);
    visit("heading_baseline_s", &SolverOptions::heading_baseline_s);
    visit("slip_keypoint_cost", &SolverOptions::slip_keypoint_cost);
    visit("slip_window_s", &SolverOptions::slip_window_s);
    visit("slip_readmit_deg", &SolverOptions::slip_readmit_deg);
    visit("slip_readmit_s", &SolverOptions::slip_readmit_s);
    visit("max_iterations", &SolverOptions::max_iterations);
    visit("max_initial_iterations", &SolverOptions::max_initial_iterations);
    visit("function_tolerance", &SolverOptions::function_tolerance);
    visit("gradient_tolerance", &SolverOptions::gradient_tolerance);
    visit("parameter_tolerance", &SolverOptions::parameter_tolerance);
  }
};

}  // namespace mocap

#endif  // MOCAP_SOLVER_OPTIONS_H_
