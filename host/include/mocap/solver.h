// The per-frame skeleton solve (slides "Overview" and "Cost function"):
//   E(theta) = E_R + E_P + E_A + E_PP + E_PD
// and, on frames without E_A, E_M in its place (residuals/motion_residual.h),
// minimised by Levenberg-Marquardt (src/lm_solver.h, over the skeleton's chain blocks),
// warm-started from the previous frame.
// The first frame (or the first after Reset) starts from InitialPose (initialisation.h).
#ifndef MOCAP_SOLVER_H_
#define MOCAP_SOLVER_H_

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "mocap/camera.h"
#include "mocap/kinematics.h"
#include "mocap/observations.h"
#include "mocap/prior.h"
#include "mocap/residuals/pca_prior_residuals.h"
#include "mocap/sites.h"
#include "mocap/skeleton.h"
#include "mocap/slip_monitor.h"
#include "mocap/solver_options.h"

namespace mocap {

struct CleanFrame;     // src/frame_validation.h
class FrameProblem;    // src/frame_problem.h
struct GroundContact;  // src/frame_problem.h

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
  // Whether IMU site i is left out of the solve: the keypoints contradict it (slip_monitor.h).
  bool distrusted(int i) const { return slips_.distrusted(i); }
  // Replaces the calibration (a skeleton with the same bones, names and parents; a layout
  // with as many keypoints; any IMU sites on its bones) from the next frame on, the pose and
  // its history kept: a calibration refined during capture. The heading corrections start
  // again from zero (the references are new) and E_A from the next two solves. False with
  // *error, nothing changed, when it does not fit (CheckCalibration).
  bool SetCalibration(Skeleton skeleton, KeypointLayout layout, std::vector<ImuSite> imus,
                      std::string* error);
  // Whether SetCalibration would take this calibration; false with *error saying why not.
  bool CheckCalibration(const Skeleton& skeleton, const KeypointLayout& layout,
                        const std::vector<ImuSite>& imus, std::string* error) const;
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
  // E_M's points (motion_points_) carry the same state without a measured acceleration:
  // v_pred = v, and g = motion_velocity_gain.
  struct MotionState {
    double timestamp = 0, step = 0;  // t1, h1 (s)
    std::vector<Eigen::Vector3d> position;
    std::vector<std::optional<Eigen::Vector3d>> velocity, accel;
    std::vector<Eigen::Vector3d> point_position;                 // of motion_points_
    std::vector<std::optional<Eigen::Vector3d>> point_velocity;  // of motion_points_
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
  // pose: the solved theta_'s forward kinematics (as for the next two).
  void Remember(const CleanFrame& frame, const BodyPose& pose, bool position_constrained,
                Continuity continuity);
  // (Re)builds the prior terms' constant matrices when their weights changed.
  void UpdatePriorResiduals();
  // Moves the heading corrections towards the solved pose's (heading_time_constant).
  void TrackHeadings(const CleanFrame& frame, const BodyPose& pose);
  // Turns each IMU's world orientation and acceleration by its heading correction.
  void TurnByHeadings(CleanFrame* frame) const;
  // The optimisation of a frame from *x: a coarse pass first when (re)initialising, the fine
  // pass, then a re-acquisition when the tracked pose lost the keypoints (max_keypoint_cost),
  // and a re-initialisation when they still cannot reach it (solver_passes.cc). False, with
  // the status and message in *result, when a pass fails.
  bool SolvePasses(const CleanFrame& frame, double timestamp, bool initialising, bool reacquiring,
                   Eigen::VectorXd* x, SolveResult* result, Continuity* continuity) const;
  // The coarse pass from *x (a nearly quadratic position loss, no motion terms); false, with
  // the message in *result, when it fails.
  bool CoarsePass(const CleanFrame& frame, int iterations, Eigen::VectorXd* x,
                  SolveResult* result) const;
  // A recovery: the frame solved from `start` (coarse and fine pass, no motion terms; `before`
  // the result before the fine pass), taken with `flag` and continuity kRestarted when it at
  // least halves the mean keypoint cost of *result; else nothing changes.
  void Recover(const CleanFrame& frame, const Eigen::VectorXd& start, int iterations,
               const SolveResult& before, QualityFlag flag, Eigen::VectorXd* x, SolveResult* result,
               Continuity* continuity) const;
  // The keypoints of a solution sit in the loss's tail: their mean cost is over
  // max_keypoint_cost (mapped to the frame's loss: wider where no IMU orients the bones).
  bool InLossTail(const SolveResult& result, const CleanFrame& frame) const;
  // After a solve (pose its solution): the sensors it left out into *result, and, when it
  // tracked the keypoints, what they say of each sensor (slip_monitor.h).
  void WatchSensors(const CleanFrame& frame, const BodyPose& pose, bool tracked,
                    SolveResult* result);
  // The warm start of a frame at `timestamp`.
  Eigen::VectorXd WarmStart(double timestamp) const;
  // Sets motion_points_ for the skeleton.
  void ChooseMotionPoints();
  // E_M (`motion`: MotionTerm) on each motion point with a velocity, when the frame at
  // `timestamp` has no E_A term in *problem (the motion state is usable: AccelerationUsable).
  void AddMotionTerms(double timestamp, const TermOptions& motion, FrameProblem* problem) const;
  // E_M's options on a frame with (oriented) or without an IMU orientation term.
  TermOptions MotionTerm(bool oriented) const;
  // E_PP and E_PD, when there is a prior and they are on.
  void AddPriorTerms(FrameProblem* problem) const;
  // Whether an IMU orientation term (E_R) enters the frame's solve.
  bool OrientationObserved(const CleanFrame& frame) const;
  // E_R of each trusted IMU with an orientation, and E_A (use_acceleration) of each with a
  // velocity and an acceleration; the distrusted sensors' orientations counted in *result.
  void AddImuTerms(const CleanFrame& frame, bool use_acceleration, FrameProblem* problem,
                   SolveResult* result) const;
  // E_G's contact sites, floor and options (no contacts when the floor is unknown or E_G off).
  GroundContact Ground() const;
  // The motion terms' information on the root's position at `timestamp` (prediction_shift.h's
  // W): those E_A or E_M (`motion`) would add, each (2 / (h2 (h1 + h2)))^2 times its weight.
  double MotionInformation(double timestamp, const TermOptions& motion) const;
  // Whether the prediction shift can change the frame: some direction the keypoints and ground
  // contact observe (root_information) less than the motion terms (prediction_shift.h).
  bool ShiftMatters(const Eigen::Matrix3d& root_information, double timestamp,
                    const TermOptions& motion) const;
  // One Levenberg-Marquardt solve of the frame from *x, with the motion terms when
  // use_acceleration (E_A, or E_M where no IMU measures acceleration). False (status and
  // message set in *result) when nothing constrains the pose or the optimiser fails.
  bool Optimise(const CleanFrame& frame, int max_iterations, double position_loss_boost,
                bool use_acceleration, Eigen::VectorXd* x, SolveResult* result) const;

  Skeleton skeleton_;
  Rig rig_;
  KeypointLayout layout_;
  std::vector<ImuSite> imus_;
  // E_M's points: every joint centre (the root's, and each bone origin apart from its parent's).
  // Not the IMU sites: E_M is for frames without E_A, above all video-only takes, which have
  // none. Joint centres lie on every bone of each chain, so they hold each bone's position and,
  // through its children's, its direction; they are what the solve outputs (joints.csv,
  // PoseFrame.joints); and each bone counts once, whatever a detector puts on it (keypoint
  // sites would weigh the head by its face points). End bones' rotations (head, hands, toes)
  // are the keypoints' and the prior's. The layout's keypoint sites instead were tried on the
  // Balancing take: the same trade-off of jitter against lag, with more points.
  std::vector<Site> motion_points_;
  std::vector<Site> contact_sites_;  // E_G's candidates: the feet's (ground.h)
  std::optional<PosePrior> prior_;
  SolverOptions options_;

  Eigen::VectorXd theta_;
  bool initialised_ = false;
  bool warm_start_given_ = false;     // SetWarmStart since the last solve: no prediction
  bool calibration_changed_ = false;  // SetCalibration since the last solve
  std::vector<SolvedFrame> history_;  // up to two previous solved frames, newest last
  std::optional<MotionState> motion_;
  std::optional<double> last_fix_;  // time of the newest solve with keypoints
  std::vector<double> headings_;    // psi_i, rad
  struct HeadingBaseline {
    double seconds = 0, yaw_integral = 0;  // of tracked frames so far
  };
  std::vector<HeadingBaseline> heading_baselines_;
  std::optional<double> last_heading_update_;
  SlipMonitor slips_;
  std::unique_ptr<LinearPriorResidual> pca_projection_, pca_deviation_;
  double pca_projection_weight_ = -1, pca_deviation_weight_ = -1;
};

}  // namespace mocap

#endif  // MOCAP_SOLVER_H_
