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
  // E_A compares the measured acceleration with the second difference of solved
  // positions, whose own jitter (~5 mm at 60 Hz) is ~20 m/s^2: hence a soft 30 m/s^2.
  TermOptions acceleration{true, 1.0 / (30.0 * 30.0), LossType::kCauchy, 1.0};
  TermOptions pca_projection{true, 1.0 / (0.15 * 0.15), LossType::kTrivial, 1.0};  // 0.15 rad
  // One standard deviation of the prior costs as much as a keypoint at its typical error;
  // weaker, the DOF the data leave free (toe, hand, clavicle twist) wander (issue 3 eval).
  TermOptions pca_deviation{true, 1.0, LossType::kTrivial, 1.0};

  Eigen::Vector3d accel_at_rest{0, 0, 9.80665};  // a_g: stationary accelerometer, world, m/s^2
  double min_confidence = 0.05;                  // detections at or below are "not detected"
  double max_quaternion_error = 1e-3;            // | |q| - 1 | above this: the reading is rejected
  double max_history_gap = 0.25;  // s: older solved frames do not feed E_A or prediction
  // Warm start from a constant-velocity prediction of the two previous solutions (on
  // SO(3) per joint) instead of the previous solution alone.
  bool predict_motion = true;
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
  const SolverOptions& options() const { return options_; }
  // Replaces the options (weights, losses, tolerances) from the next frame on; false and
  // *error set, options unchanged, when they are out of range.
  bool SetOptions(const SolverOptions& options, std::string* error);

 private:
  struct SolvedFrame {
    double timestamp;
    Eigen::VectorXd theta;
    std::vector<Eigen::Vector3d> imu_sites;  // world positions of each IMU site
    bool position_constrained;               // keypoints took part in the solve
  };
  // The two previous solves, within max_history_gap of each other and of `timestamp`, in
  // one regime (both with keypoints, or both without): across a change of regime, their
  // difference holds the re-acquisition jump, not the motion, and extrapolating it (E_A,
  // the warm-start prediction) runs away.
  bool HistoryUsable(double timestamp) const;

  Solver() = default;
  void Remember(const CleanFrame& frame, bool position_constrained);
  // (Re)builds the prior terms' constant matrices when their weights changed.
  void UpdatePriorResiduals();
  // The warm start of a frame at `timestamp`.
  Eigen::VectorXd WarmStart(double timestamp) const;
  // One Levenberg-Marquardt solve of the frame from *x. False (status and message set in
  // *result) when nothing constrains the pose or the optimiser fails.
  bool Optimise(const CleanFrame& frame, int max_iterations, double position_loss_boost,
                Eigen::VectorXd* x, SolveResult* result) const;

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
  // Measured world acceleration a(t1) of each IMU at the newest solved frame.
  std::vector<std::optional<Eigen::Vector3d>> last_accel_;
  std::unique_ptr<ceres::CostFunction> pca_projection_, pca_deviation_;
  double pca_projection_weight_ = -1, pca_deviation_weight_ = -1;
};

}  // namespace mocap

#endif  // MOCAP_SOLVER_H_
