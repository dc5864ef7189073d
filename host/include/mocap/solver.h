// The per-frame skeleton solve (slides "Overview" and "Cost function"):
//   E(theta) = E_R + E_P + E_A + E_PP + E_PD
// minimised by Levenberg-Marquardt (Ceres), warm-started from the previous frame.
// The first frame (or the first after Reset) starts from InitialPose (initialisation.h).
#ifndef MOCAP_SOLVER_H_
#define MOCAP_SOLVER_H_

#include <ceres/cost_function.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "mocap/camera.h"
#include "mocap/kinematics.h"
#include "mocap/observations.h"
#include "mocap/prior.h"
#include "mocap/sites.h"
#include "mocap/skeleton.h"

namespace mocap {

struct CleanFrame;  // src/frame_validation.h

enum class LossType { kTrivial, kCauchy, kHuber };

// One cost term: E = rho(weight * |e|^2), rho scaled by loss_scale (rho(s) = a log(1 + s/a)
// for Cauchy with a = loss_scale). Units of weight are the inverse square of the term's.
struct TermOptions {
  bool enabled = true;
  double weight = 1.0;
  LossType loss = LossType::kTrivial;
  double loss_scale = 1.0;
};

struct SolverOptions {
  // Weights: 1 / (typical error)^2 of each measurement, so a typical error costs ~1.
  TermOptions orientation{true, 1.0 / (0.035 * 0.035), LossType::kCauchy, 4.0};  // 2 degrees
  TermOptions position{true, 1.0 / 25.0, LossType::kCauchy, 1.0};                // 5 pixels
  // E_A compares the measured acceleration with the second difference of the solved
  // positions, whose previous velocity is filtered (velocity_gain): 18 m/s^2 and the gain
  // 0.3 were tuned on the validation clips (docs/results.md, "Tuning").
  TermOptions acceleration{true, 1.0 / (18.0 * 18.0), LossType::kCauchy, 1.0};
  TermOptions pca_projection{true, 1.0 / (0.15 * 0.15), LossType::kTrivial, 1.0};  // 0.15 rad
  // One standard deviation of the prior costs as much as a keypoint at its typical error;
  // weaker, the DOF the data leave free (toe, hand, clavicle twist) wander (issue 3 eval).
  TermOptions pca_deviation{true, 1.0, LossType::kTrivial, 1.0};

  Eigen::Vector3d accel_at_rest{0, 0, 9.80665};  // a_g: stationary accelerometer, world, m/s^2
  double min_confidence = 0.05;                  // detections at or below are "not detected"
  double max_quaternion_error = 1e-3;            // | |q| - 1 | above this: the reading is rejected
  double max_history_gap = 0.25;  // s: older solved frames do not feed E_A or prediction
  // E_A's previous velocity of each IMU site (see MotionState): 1 takes the difference of
  // the last two solutions, as the slide's second difference; below 1, a complementary
  // filter of that difference and the velocity integrated from the accelerometers.
  double velocity_gain = 0.3;
  // Mean robust cost per keypoint (rho, in the position loss's units) above which the
  // tracked pose is taken to have lost the keypoints and is re-acquired from them; a
  // tracked pose scores ~1.1, one carried off by the motion terms 4-8 (issue 3 eval).
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
  int max_iterations = 10;           // per warm-started frame
  int max_initial_iterations = 100;  // for the first frame
  // Relative cost change that ends a frame. Warm-started frames reach their accuracy in
  // 2-3 iterations; tighter tolerances add iterations, not accuracy (docs/performance.md).
  double function_tolerance = 1e-3;
  double gradient_tolerance = 1e-10;
  double parameter_tolerance = 1e-8;

  bool IsValid(std::string* error) const;
};

// Fits theta (in place, from its current value) to 3D target points of sites by least
// squares; targets with a non-positive or non-finite weight (1/m^2) are ignored. Returns
// false when nothing was fitted. Not one of the paper's terms: it serves the video-only
// baseline of the evaluation and retargeting.
bool FitToPoints(const Skeleton& skeleton, const std::vector<Site>& sites,
                 const std::vector<Eigen::Vector3d>& targets, const std::vector<double>& weights,
                 int max_iterations, Eigen::VectorXd* theta);

class Solver {
 public:
  // Returns null and sets *error when an input is inconsistent. prior may be empty:
  // then the PCA terms are off whatever the options say.
  static std::unique_ptr<Solver> Create(Skeleton skeleton, Rig rig, KeypointLayout layout,
                                        std::vector<ImuSite> imus, std::optional<PosePrior> prior,
                                        SolverOptions options, std::string* error);

  // Solves one frame. Never throws; result.theta is always finite.
  SolveResult Solve(const FrameObservations& frame);

  // Forget the motion: the next frame is initialised again.
  void Reset();
  // The next frame starts from theta exactly (keeps the motion history).
  void SetWarmStart(const Eigen::VectorXd& theta);

  const Eigen::VectorXd& pose() const { return theta_; }
  bool initialised() const { return initialised_; }
  const Skeleton& skeleton() const { return skeleton_; }
  const Rig& rig() const { return rig_; }
  const KeypointLayout& layout() const { return layout_; }
  const std::vector<ImuSite>& imus() const { return imus_; }
  // The heading corrections psi_i (rad, about world z), one per IMU site: the reference in
  // use is Rz(psi_i) * imus()[i].reference.
  const std::vector<double>& headings() const { return headings_; }
  const SolverOptions& options() const { return options_; }
  // Replaces the calibration (a skeleton with the same bones, names and parents; a layout
  // with as many keypoints; any IMU sites on its bones) from the next frame on, the pose and
  // its history kept: a calibration refined during capture. The heading corrections start
  // again from zero (the references are new) and E_A from the next two solves. False with
  // *error, nothing changed, when it does not fit.
  bool SetCalibration(Skeleton skeleton, KeypointLayout layout, std::vector<ImuSite> imus,
                      std::string* error);
  // Replaces the options (weights, losses, tolerances) from the next frame on; false and
  // *error set, options unchanged, when they are out of range.
  bool SetOptions(const SolverOptions& options, std::string* error);

 private:
  struct SolvedFrame {
    double timestamp;
    Eigen::VectorXd theta;
    bool position_constrained;  // keypoints took part in the solve
  };
  // What E_A knows of each IMU site's motion at the newest solved frame t1:
  //   x(t1), the measured acceleration a(t1), and v, the site's mean velocity over the
  //   step [t1 - h1, t1] (absent until two frames were solved in a row).
  // After a frame at t (h2 = t - t1): v_pred = v + a(t1) (h1 + h2) / 2, the raw velocity
  // (x(t) - x(t1)) / h2, and v <- v_pred + g (raw - v_pred) with g = velocity_gain. When
  // keypoints return after frames without them (re-acquisition), the jump is the drift of
  // the dead reckoning since the last keypoints at t_fix: g = h2 / (t - t_fix) spreads it
  // over that time, so the velocity is corrected rather than the jump taken for motion.
  struct MotionState {
    double timestamp = 0, step = 0;  // t1, h1 (s)
    std::vector<Eigen::Vector3d> position;
    std::vector<std::optional<Eigen::Vector3d>> velocity, accel;
  };
  // E_A applies at `timestamp` (the state is within max_history_gap, no re-acquisition).
  bool AccelerationUsable(double timestamp, bool reacquiring) const;
  // The two previous solves feed the warm-start prediction when they lie within
  // max_history_gap of each other and of `timestamp`, in one regime (both with keypoints,
  // or both without): across a change of regime their difference holds the re-acquisition
  // jump, not the motion.
  bool PredictionUsable(double timestamp) const;

  Solver() = default;
  // How a solve continues the previous: tracked, re-acquired after frames without
  // keypoints (the jump is drift), or restarted after the keypoints were lost (the motion
  // state's velocities are forgotten).
  enum class Continuity { kContinuous, kReacquired, kRestarted };
  void Remember(const CleanFrame& frame, bool position_constrained, Continuity continuity);
  // (Re)builds the prior terms' constant matrices when their weights changed.
  void UpdatePriorResiduals();
  // Moves the heading corrections towards the solved pose's (heading_time_constant).
  void TrackHeadings(const CleanFrame& frame);
  // The warm start of a frame at `timestamp`.
  Eigen::VectorXd WarmStart(double timestamp) const;
  // One Levenberg-Marquardt solve of the frame from *x. False (status and message set in
  // *result) when nothing constrains the pose or the optimiser fails.
  bool Optimise(const CleanFrame& frame, int max_iterations, double position_loss_boost,
                bool use_acceleration, Eigen::VectorXd* x, SolveResult* result) const;

  Skeleton skeleton_;
  Rig rig_;
  KeypointLayout layout_;
  std::vector<ImuSite> imus_;
  std::optional<PosePrior> prior_;
  SolverOptions options_;

  Eigen::VectorXd theta_;
  bool initialised_ = false;
  bool warm_start_given_ = false;     // SetWarmStart since the last solve: no prediction
  std::vector<SolvedFrame> history_;  // up to two previous solved frames, newest last
  std::optional<MotionState> motion_;
  std::optional<double> last_fix_;  // time of the newest solve with keypoints
  std::vector<double> headings_;    // psi_i, rad
  struct HeadingBaseline {
    double seconds = 0, yaw_integral = 0;  // of tracked frames so far
  };
  std::vector<HeadingBaseline> heading_baselines_;
  std::optional<double> last_heading_update_;
  std::unique_ptr<ceres::CostFunction> pca_projection_, pca_deviation_;
  double pca_projection_weight_ = -1, pca_deviation_weight_ = -1;
};

}  // namespace mocap

#endif  // MOCAP_SOLVER_H_
