#include "mocap/solver.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>

#include "frame_problem.h"
#include "frame_validation.h"
#include "mocap/ground.h"
#include "mocap/initialisation.h"
#include "mocap/residuals/pca_prior_residuals.h"
#include "mocap/so3.h"

namespace mocap {

const char* ToString(SolveStatus status) {
  switch (status) {
    case SolveStatus::kOk:
      return "ok";
    case SolveStatus::kInitialised:
      return "initialised";
    case SolveStatus::kNoObservations:
      return "no_observations";
    case SolveStatus::kRejectedFrame:
      return "rejected_frame";
    case SolveStatus::kFailed:
      return "failed";
  }
  return "unknown";
}

namespace {

// Levenberg-Marquardt on normal equations accumulated over each residual's chain blocks
// (lm_solver.h), with Ceres' trust-region defaults and tolerances (docs/performance.md).
LmOptions LmOptionsOf(const SolverOptions& options, int max_iterations) {
  LmOptions lm;
  lm.max_iterations = max_iterations;
  lm.function_tolerance = options.function_tolerance;
  lm.gradient_tolerance = options.gradient_tolerance;
  lm.parameter_tolerance = options.parameter_tolerance;
  return lm;
}

bool Active(const TermOptions& t) { return t.enabled && t.weight > 0.0; }

// The prediction shift (prediction_shift.h). r: a direction counts as observed where the
// keypoints' information on the root exceeds ~1% of the motion terms' own (one camera's depth
// has ~0.1%, its other directions ~7%, eight cameras 20-40%). sigma_max (metres): the shift's
// scale where the keypoints see nothing, a frame of a run and more.
constexpr double kObservedInformationRatio = 0.01;
constexpr double kMaxPredictionShift = 0.2;
// A frame whose every direction the shift would loosen by less than this is solved without it
// (3 parameters fewer, the motion terms in their bones' groups: the solver benchmark's eight
// cameras, x ~ 0.5, 3.5%).
constexpr double kNegligibleLoosening = 0.1;
// A solved root farther than this (metres) from every camera is refused (status kFailed, the
// previous pose held): cameras see a person within tens of metres, and a pose kilometres
// away is a depth no view supports (a monocular guess, inputs on another clock).
constexpr double kMaxCameraDistance = 100.0;

// False, with the status and message in *result, when the rig has cameras and the root of
// `theta` is beyond kMaxCameraDistance from all of them.
bool WithinReach(const Rig& rig, const Eigen::VectorXd& theta, SolveResult* result) {
  double nearest = INFINITY;
  for (const Camera& c : rig.cameras)
    nearest = std::min(nearest, (c.Center() - theta.head<3>()).norm());
  if (rig.cameras.empty() || nearest <= kMaxCameraDistance) return true;
  result->status = SolveStatus::kFailed;
  result->message = "the solved pose is " + std::to_string(static_cast<int>(nearest)) +
                    " m from the nearest camera (more than 100 m: no view supports it)";
  return false;
}

// The layout's and the IMU sites' bones are the skeleton's.
bool CheckSites(const Skeleton& skeleton, const KeypointLayout& layout,
                const std::vector<ImuSite>& imus, std::string* error) {
  if (skeleton.num_bones() == 0) return *error = "empty skeleton", false;
  for (const Site& s : layout.sites) {
    if (s.bone < 0 || s.bone >= skeleton.num_bones() || !s.offset.allFinite())
      return *error = "layout '" + layout.name + "' has a site on an unknown bone", false;
  }
  for (const ImuSite& s : imus) {
    if (s.bone < 0 || s.bone >= skeleton.num_bones() || !s.offset.allFinite() ||
        !s.mount.allFinite() || !s.reference.allFinite())
      return *error = "IMU '" + s.name + "' is on an unknown bone or not finite", false;
  }
  return true;
}

}  // namespace

std::unique_ptr<Solver> Solver::Create(Skeleton skeleton, Rig rig, KeypointLayout layout,
                                       std::vector<ImuSite> imus, std::optional<PosePrior> prior,
                                       SolverOptions options, std::string* error) {
  for (const Camera& c : rig.cameras) {
    if (!c.IsValid(error)) return nullptr;
  }
  if (!CheckSites(skeleton, layout, imus, error)) return nullptr;
  if (prior) {
    if (!prior->IsValid(error)) return nullptr;
    if (prior->dof() != skeleton.pose_dim() - 6) {
      *error = "prior has " + std::to_string(prior->dof()) + " DOF, the skeleton " +
               std::to_string(skeleton.pose_dim() - 6);
      return nullptr;
    }
  }
  if (!options.IsValid(error)) return nullptr;
  std::unique_ptr<Solver> s(new Solver());
  s->skeleton_ = std::move(skeleton);
  s->rig_ = std::move(rig);
  s->layout_ = std::move(layout);
  s->imus_ = std::move(imus);
  s->prior_ = std::move(prior);
  s->options_ = options;
  s->headings_.assign(s->imus_.size(), 0.0);
  s->heading_baselines_.assign(s->imus_.size(), {});
  s->slips_ = SlipMonitor(s->skeleton_, s->layout_, s->imus_);
  s->ChooseMotionPoints();
  s->contact_sites_ = FootContactSites(s->skeleton_);
  s->Reset();
  return s;
}

void Solver::Reset() {
  theta_ = Eigen::VectorXd::Zero(skeleton_.pose_dim());
  initialised_ = false;
  history_.clear();
  motion_.reset();
  last_fix_.reset();
  last_heading_update_.reset();  // the corrections themselves are calibration: kept
}

bool FitToPoints(const Skeleton& skeleton, const std::vector<Site>& sites,
                 const std::vector<Eigen::Vector3d>& targets, const std::vector<double>& weights,
                 int max_iterations, Eigen::VectorXd* theta) {
  if (theta->size() != skeleton.pose_dim() || sites.size() != targets.size() ||
      sites.size() != weights.size()) {
    return false;
  }
  FrameProblem problem(skeleton, theta->data());
  for (size_t i = 0; i < sites.size(); ++i) {
    if (!(weights[i] > 0.0) || !std::isfinite(weights[i]) || !targets[i].allFinite() ||
        sites[i].bone < 0 || sites[i].bone >= skeleton.num_bones()) {
      continue;
    }
    problem.AddPointTerm(sites[i], targets[i],
                         TermOptions{true, weights[i], LossType::kTrivial, 1.0});
  }
  if (problem.count(kPointTerm) == 0) return false;
  SolverOptions fit;
  fit.function_tolerance = 1e-6;
  const LmSummary summary = problem.Solve(LmOptionsOf(fit, max_iterations));
  return summary.termination != LmTermination::kFailed && theta->allFinite();
}

bool Solver::CheckCalibration(const Skeleton& skeleton, const KeypointLayout& layout,
                              const std::vector<ImuSite>& imus, std::string* error) const {
  if (skeleton.num_bones() != skeleton_.num_bones())
    return *error = "the calibration's skeleton has other bones than the solver's", false;
  for (int b = 0; b < skeleton.num_bones(); ++b) {
    if (skeleton.bone(b).name != skeleton_.bone(b).name ||
        skeleton.bone(b).parent != skeleton_.bone(b).parent)
      return *error = "the calibration's skeleton has other bones than the solver's (bone '" +
                      skeleton.bone(b).name + "')",
             false;
  }
  if (layout.size() != layout_.size())
    return *error = "the calibration's layout has " + std::to_string(layout.size()) +
                    " keypoints, the solver's " + std::to_string(layout_.size()),
           false;
  return CheckSites(skeleton, layout, imus, error);
}

bool Solver::SetCalibration(Skeleton skeleton, KeypointLayout layout, std::vector<ImuSite> imus,
                            std::string* error) {
  if (!CheckCalibration(skeleton, layout, imus, error)) return false;
  skeleton_ = std::move(skeleton);
  layout_ = std::move(layout);
  imus_ = std::move(imus);
  headings_.assign(imus_.size(), 0.0);
  heading_baselines_.assign(imus_.size(), {});
  last_heading_update_.reset();
  slips_ = SlipMonitor(skeleton_, layout_, imus_);
  ChooseMotionPoints();
  contact_sites_ = FootContactSites(skeleton_);
  motion_.reset();   // the sites moved: E_A starts again from the next two solves
  history_.clear();  // poses of the old skeleton: their difference is no motion
  calibration_changed_ = true;
  return true;
}

bool Solver::SetOptions(const SolverOptions& options, std::string* error) {
  if (!options.IsValid(error)) return false;
  options_ = options;
  return true;
}

void Solver::SetWarmStart(const Eigen::VectorXd& theta) {
  if (theta.size() != skeleton_.pose_dim() || !theta.allFinite()) return;
  theta_ = theta;
  initialised_ = true;
  warm_start_given_ = true;
}

void Solver::UpdatePriorResiduals() {
  if (!prior_) return;
  if (prior_->rank() < prior_->dof() && options_.pca_projection.weight != pca_projection_weight_) {
    pca_projection_ =
        std::make_unique<PcaProjectionResidual>(*prior_, options_.pca_projection.weight);
    pca_projection_weight_ = options_.pca_projection.weight;
  }
  if (options_.pca_deviation.weight != pca_deviation_weight_) {
    pca_deviation_ = std::make_unique<PcaDeviationResidual>(*prior_, options_.pca_deviation.weight);
    pca_deviation_weight_ = options_.pca_deviation.weight;
  }
}

void Solver::AddPriorTerms(FrameProblem* problem) const {
  if (pca_projection_ && Active(options_.pca_projection)) {
    problem->AddPriorTerm(kPcaProjectionTerm, pca_projection_.get(), options_.pca_projection);
  }
  if (pca_deviation_ && Active(options_.pca_deviation)) {
    problem->AddPriorTerm(kPcaDeviationTerm, pca_deviation_.get(), options_.pca_deviation);
  }
}

GroundContact Solver::Ground() const {
  GroundContact ground;
  if (Active(options_.ground) && std::isfinite(options_.floor_height)) {
    ground.contacts = &contact_sites_;
    ground.floor = options_.floor_height;
    ground.options = options_.ground;
  }
  return ground;
}

bool Solver::ShiftMatters(const Eigen::Matrix3d& root_information, double timestamp,
                          const TermOptions& motion) const {
  const double w = MotionInformation(timestamp, motion);
  if (!(w > 0.0)) return false;
  // The weakest direction's x = h / W, where the shift loosens the motion terms' pull on the
  // root by the factor 1 + kappa / (x (1 + x / r)) (prediction_shift.h).
  const double x =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(root_information, Eigen::EigenvaluesOnly)
          .eigenvalues()[0] /
      w;
  return options_.prediction_slack >=
         kNegligibleLoosening * x * (1.0 + x / kObservedInformationRatio);
}

void Solver::AddImuTerms(const CleanFrame& frame, bool use_acceleration, FrameProblem* problem,
                         SolveResult* result) const {
  for (size_t i = 0; i < imus_.size(); ++i) {
    if (slips_.distrusted(static_cast<int>(i))) {
      result->counts.orientations_distrusted += frame.imu_world[i].has_value();
      continue;
    }
    if (frame.imu_world[i] && Active(options_.orientation)) {
      problem->AddOrientationTerm(imus_[i], *frame.imu_world[i], options_.orientation);
    }
    if (use_acceleration && motion_->velocity[i] && motion_->accel[i] &&
        Active(options_.acceleration)) {
      // The previous step's velocity stands in for x(t0): x(t1) - v h1 (MotionState).
      const Eigen::Vector3d& x1 = motion_->position[i];
      problem->AddAccelerationTerm(imus_[i], x1, x1 - *motion_->velocity[i] * motion_->step,
                                   motion_->step, frame.timestamp - motion_->timestamp,
                                   *motion_->accel[i], options_.acceleration);
    }
  }
}

bool Solver::Optimise(const CleanFrame& frame, int max_iterations, double position_loss_boost,
                      bool use_acceleration, Eigen::VectorXd* x, SolveResult* result) const {
  const bool oriented = OrientationObserved(frame);
  const TermOptions motion = MotionTerm(oriented);
  // The motion terms' prediction may shift where the keypoints can pull it (prediction_shift.h).
  Eigen::Matrix3d root_information = Eigen::Matrix3d::Zero();
  bool shift = use_acceleration && !frame.detections.empty() && options_.prediction_slack > 0;
  if (shift) {
    root_information = RootPositionInformation(skeleton_, x->data(), rig_, layout_,
                                               frame.detections, options_.position, Ground());
    shift = ShiftMatters(root_information, frame.timestamp, motion);
  }
  FrameProblem problem(skeleton_, x->data(), shift);
  if (Active(options_.position)) {
    TermOptions position = options_.position;
    position.loss_scale *= position_loss_boost;
    if (!oriented) position.loss_scale *= options_.video_only_position_loss_scale;
    result->counts.keypoints_behind_camera +=
        problem.AddPositionTerms(rig_, layout_, frame.detections, position);
  }
  if (const GroundContact ground = Ground(); ground.contacts != nullptr) {
    TermOptions floor = ground.options;  // wider where nothing else holds the height
    if (frame.detections.empty()) floor.loss_scale *= options_.ground_unobserved_scale;
    problem.AddGroundTerm(*ground.contacts, ground.floor, floor);
  }
  AddImuTerms(frame, use_acceleration, &problem, result);
  if (use_acceleration) AddMotionTerms(frame.timestamp, motion, &problem);
  problem.AddPredictionShiftPrior(root_information, options_.prediction_slack,
                                  kObservedInformationRatio, kMaxPredictionShift);
  AddPriorTerms(&problem);
  result->counts.keypoints_used = problem.count(kPositionTerm);
  result->counts.orientations_used = problem.count(kOrientationTerm);
  result->counts.accelerations_used = problem.count(kAccelerationTerm);
  if (problem.count(kPositionTerm) == 0 && problem.count(kOrientationTerm) == 0) {
    result->status = SolveStatus::kNoObservations;
    result->message = "every detection was behind its camera or a term is off";
    return false;
  }

  const LmSummary summary = problem.Solve(LmOptionsOf(options_, max_iterations));
  result->iterations = summary.iterations;
  result->timings = {summary.total_ms, summary.linear_solver_ms, summary.jacobian_ms,
                     summary.residual_ms};
  if (summary.termination == LmTermination::kFailed || !x->allFinite()) {
    result->status = SolveStatus::kFailed;
    result->message = "optimiser failed: " + summary.message;
    return false;
  }
  if (summary.termination == LmTermination::kIterationLimit) result->flags |= kIterationLimit;
  if (problem.count(kPositionTerm) == 0) result->flags |= kPositionUnconstrained;
  if (problem.count(kAccelerationTerm) == 0) result->flags |= kAccelerationUnavailable;
  result->costs = problem.Costs();
  return true;
}

void Solver::WatchSensors(const CleanFrame& clean, const BodyPose& pose, bool tracked,
                          SolveResult* result) {
  for (int i = 0; i < slips_.size(); ++i) {
    if (slips_.distrusted(i)) result->imus_distrusted.push_back(i);
  }
  if (!tracked || clean.detections.empty()) return;
  slips_.Update(clean.timestamp, options_, rig_, layout_, pose, clean.detections, clean.imu_world);
}

SolveResult Solver::Solve(const FrameObservations& frame) {
  const auto start = std::chrono::steady_clock::now();
  SolveResult result;
  result.timestamp = frame.timestamp;
  auto finish = [&](SolveStatus status, std::string message) {
    result.status = status;
    result.message = std::move(message);
    result.theta = theta_;
    result.solve_time_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return result;
  };

  if (!std::isfinite(frame.timestamp) ||
      (!history_.empty() && frame.timestamp <= history_.back().timestamp)) {
    return finish(SolveStatus::kRejectedFrame,
                  "timestamp not finite or not after the previous frame");
  }
  CleanFrame clean = ValidateFrame(frame, rig_, layout_, imus_, options_, &result.counts);
  TurnByHeadings(&clean);
  int orientations = 0;
  for (const auto& o : clean.imu_world) orientations += o.has_value();
  if (clean.detections.empty() && orientations == 0) {
    return finish(SolveStatus::kNoObservations, "no usable keypoint or IMU orientation");
  }

  UpdatePriorResiduals();
  const bool initialising = !initialised_;
  Eigen::VectorXd x = WarmStart(frame.timestamp);
  warm_start_given_ = false;
  if (initialising) {
    x = EstimateInitialPose(skeleton_, rig_, layout_, imus_, clean.detections, clean.imu_world)
            .theta;
  }
  // Keypoints again after frames without them (a camera outage, HS mode): the pose has
  // drifted and is re-acquired like a first frame.
  const bool reacquiring = !initialising && !clean.detections.empty() && !history_.empty() &&
                           !history_.back().position_constrained;
  Continuity continuity = Continuity::kContinuous;
  if (!SolvePasses(clean, frame.timestamp, initialising, reacquiring, &x, &result, &continuity) ||
      !WithinReach(rig_, x, &result))
    return finish(result.status, result.message);
  theta_ = x;
  initialised_ = true;
  calibration_changed_ = false;
  BodyPose pose;
  ForwardKinematics(skeleton_, theta_.data(), &pose);
  WatchSensors(clean, pose, continuity == Continuity::kContinuous && !initialising, &result);
  Remember(clean, pose, !(result.flags & kPositionUnconstrained), continuity);
  // Only a tracked pose the keypoints hold tells the headings anything.
  if (continuity == Continuity::kContinuous && !initialising &&
      !(result.flags & kPositionUnconstrained)) {
    TrackHeadings(clean, pose);
  }
  return finish(initialising ? SolveStatus::kInitialised : SolveStatus::kOk, "");
}

}  // namespace mocap
