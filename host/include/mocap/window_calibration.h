// Calibration over a window of frames: the subject's bone lengths, where each keypoint of
// the detector sits on its bone, and each IMU's mounting and heading, solved jointly with
// the poses of a few seconds of ordinary motion (a bundle adjustment of the body).
//
// Unknowns: theta_t per frame; s_u per length group and d_v per shift group (bone j's offset
// becomes s_u t_j + D_j d_v: a group's lengths scale together, a shift group's offsets move
// together, mirrored left/right; residuals/calibration_residuals.h); o_k per keypoint (its offset
// in its bone's frame); per IMU a mounting M = M0 Exp(m) and a heading psi turning its reference
// frame about world z, R_ig = Rz(psi) R_ig0. Cost: the frames' E_P (keypoint reprojection, Cauchy,
// confidence-weighted), E_R with the unknown mounting and heading, E_PP and E_PD per frame, and
// Gaussian priors holding each site near the layout's (site_sigma), each scale near its start
// (scale_sigma), each shift near zero (shift_sigma) and, when given, each heading near its
// prior from elsewhere (heading_priors).
//
// Why it is observable: the IMUs give each instrumented bone's orientation up to a constant
// (mounting, heading) and video its position; as the bones turn, a keypoint's offset moves
// its projection differently from a joint's, so offsets and lengths separate from poses.
// What stays weak: a bone's twist about its own axis when no keypoint lies off the axis
// (the prior decides), and the component of a site along a hinge axis.
#ifndef MOCAP_WINDOW_CALIBRATION_H_
#define MOCAP_WINDOW_CALIBRATION_H_

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "mocap/camera.h"
#include "mocap/observations.h"
#include "mocap/prior.h"
#include "mocap/sites.h"
#include "mocap/skeleton.h"
#include "mocap/solver.h"

namespace mocap {

// A frame in which the subject is known to hold a pose (a T-pose or N-pose at the start of a
// take): each joint's rotation relative to its parent costs |theta_b - pose_b| / sigma. The
// root is left free (the subject faces any way). A held calibration pose defines the bone
// frames the way a suit's calibration does, and so pins the mountings' twist.
struct HeldPose {
  int frame = 0;          // index into the window's frames
  Eigen::VectorXd theta;  // pose_dim; only the joints' entries are used
  double sigma = 0.05;    // rad

  template <typename Visit>
  static void VisitFields(Visit&& visit) {
    visit("frame", &HeldPose::frame);
    visit("theta", &HeldPose::theta);
    visit("sigma", &HeldPose::sigma);
  }
};

// The window's terms: the solver's, but E_R keeps a robust loss. With the mountings unknown,
// a frame whose video pose is wrong (a limb's twist, a trunk on sparse detections) would
// otherwise pull every mounting and heading: on HS takes without it the trunk sensors'
// headings came out 52-131 degrees off (07_06).
inline SolverOptions WindowTerms() {
  SolverOptions o;
  o.orientation.loss = LossType::kCauchy;
  return o;
}

struct CalibrationOptions {
  SolverOptions terms = WindowTerms();  // E_R, E_P, E_PP, E_PD weights and losses; thresholds
  std::vector<int> scale_group;         // per bone: its length group, -1 for none (may be empty)
  std::vector<int> shift_group;         // per bone: its shift group, -1 for none (may be empty)
  double scale_sigma = 0.05;            // prior on each group scale around its start (relative)
  double shift_sigma = 0.05;            // m, prior on each group shift around zero
  // Per shift group, per axis (of its first bone's parent frame), overriding shift_sigma: a
  // tiny sigma holds an axis that trades with another parameter (a gauge), e.g. the hips'
  // height against the spine's length when no keypoint marks the pelvis origin.
  std::vector<Eigen::Vector3d> shift_sigmas;
  // Per bone (or empty): sigma (rad) of each component of its rotation relative to its
  // parent, in every frame; zero or infinite leaves the component free. An anatomical
  // convention that fixes what the data leave free: a knee turning about one axis only, an
  // elbow without axial twist, pin the twist of the limbs' frames and so of their IMUs'
  // mountings, which video does not see.
  std::vector<Eigen::Vector3d> joint_sigmas;
  std::vector<HeldPose> held_poses;
  // Per IMU (or empty): a prior on its heading from elsewhere (the accelerometer), as the yaw
  // of its estimated reference frame (rad, about world z) and a sigma (rad; zero or infinite:
  // none). It settles what E_R leaves free: a segment that only turns about the vertical
  // explains its readings with any heading, its mounting's yaw taking up the rest.
  std::vector<Eigen::Vector2d> heading_priors;
  double site_sigma = 0.03;  // m, prior on each keypoint site around the layout's
  // m (0: keep the whole estimate). The sites' change from the layout's is kept only along
  // the directions of the sites' joint covariance (the poses, lengths, mountings and
  // headings marginalised: ceres::Covariance) whose standard deviation is below this: what
  // the window observes. The rest, near-gauges with the poses (a whole leg's sites moving
  // together), stays at the layout's.
  double site_observable_std = 0.0;
  bool estimate_scales = true, estimate_shifts = true, estimate_sites = true,
       estimate_mounts = true, estimate_headings = true;
  int max_iterations = 60;
  int num_threads = 2;

  // True when every field is in range by itself; else *error holds one message per failing
  // condition, joined by "; ". (Sizes that depend on the window, the skeleton and the IMU
  // set are checked by CalibrateWindow.)
  bool IsValid(std::string* error) const;

  // Each field once, by name (the Python attribute): see solver_options.h.
  template <typename Visit>
  static void VisitFields(Visit&& visit) {
    visit("terms", &CalibrationOptions::terms);
    visit("scale_group", &CalibrationOptions::scale_group);
    visit("shift_group", &CalibrationOptions::shift_group);
    visit("scale_sigma", &CalibrationOptions::scale_sigma);
    visit("shift_sigma", &CalibrationOptions::shift_sigma);
    visit("shift_sigmas", &CalibrationOptions::shift_sigmas);
    visit("joint_sigmas", &CalibrationOptions::joint_sigmas);
    visit("held_poses", &CalibrationOptions::held_poses);
    visit("heading_priors", &CalibrationOptions::heading_priors);
    visit("site_sigma", &CalibrationOptions::site_sigma);
    visit("site_observable_std", &CalibrationOptions::site_observable_std);
    visit("estimate_scales", &CalibrationOptions::estimate_scales);
    visit("estimate_shifts", &CalibrationOptions::estimate_shifts);
    visit("estimate_sites", &CalibrationOptions::estimate_sites);
    visit("estimate_mounts", &CalibrationOptions::estimate_mounts);
    visit("estimate_headings", &CalibrationOptions::estimate_headings);
    visit("max_iterations", &CalibrationOptions::max_iterations);
    visit("num_threads", &CalibrationOptions::num_threads);
  }
};

struct CalibrationResult {
  Skeleton skeleton;                    // offsets scaled
  KeypointLayout layout;                // sites estimated
  std::vector<ImuSite> imus;            // mount and reference estimated (offset unchanged)
  std::vector<double> scales;           // per length group, relative to the given skeleton
  std::vector<Eigen::Vector3d> shifts;  // per shift group, m (of its first bone)
  std::vector<Eigen::VectorXd> thetas;  // the window's poses
  int site_directions_kept = 0;         // of 3 x keypoints (site_observable_std)
  // (3 x keypoints) x site_directions_kept: the kept directions, orthonormal (keypoint k's
  // rows 3k..3k+2, its offset in its bone's frame): what the window observes of the sites.
  Eigen::MatrixXd site_directions;
  std::vector<double> imu_residual_deg;    // median |E_R angle| per IMU (NaN: unseen)
  std::vector<int> keypoint_observations;  // per keypoint: detections used
  double initial_cost = 0, final_cost = 0;
  int iterations = 0;
  bool converged = false;
  std::string message;  // Ceres' summary line
};

// frames: the window's observations; thetas: their starting poses (e.g. a video-only
// solve). False with *error when inputs are inconsistent or nothing could be solved.
bool CalibrateWindow(const Skeleton& skeleton, const Rig& rig, const KeypointLayout& layout,
                     const std::vector<ImuSite>& imus, const std::optional<PosePrior>& prior,
                     const std::vector<FrameObservations>& frames,
                     const std::vector<Eigen::VectorXd>& thetas, const CalibrationOptions& options,
                     CalibrationResult* result, std::string* error);

}  // namespace mocap

#endif  // MOCAP_WINDOW_CALIBRATION_H_
