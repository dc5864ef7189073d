#include "mocap/window_calibration.h"

#include <ceres/ceres.h>
#include <ceres/normal_prior.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "frame_problem.h"
#include "frame_validation.h"
#include "mocap/residuals/calibration_residuals.h"
#include "mocap/residuals/pca_prior_residuals.h"
#include "mocap/so3.h"
#include "observed_sites.h"
#include "option_checks.h"

namespace mocap {
namespace {

bool Fail(std::string* error, const std::string& message) {
  if (error != nullptr) *error = message;
  return false;
}

bool CheckInputs(const Skeleton& skeleton, const std::vector<ImuSite>& imus,
                 const std::vector<FrameObservations>& frames,
                 const std::vector<Eigen::VectorXd>& thetas, const std::optional<PosePrior>& prior,
                 const CalibrationOptions& options, std::string* error) {
  if (frames.empty()) return Fail(error, "the calibration window has no frames");
  if (frames.size() != thetas.size())
    return Fail(error, "one starting pose per frame is needed (" + std::to_string(frames.size()) +
                           " frames, " + std::to_string(thetas.size()) + " poses)");
  for (size_t t = 0; t < thetas.size(); ++t) {
    if (thetas[t].size() != skeleton.pose_dim() || !thetas[t].allFinite())
      return Fail(error, "starting pose " + std::to_string(t) + " is not a finite " +
                             std::to_string(skeleton.pose_dim()) + "-vector");
  }
  for (const auto* group : {&options.scale_group, &options.shift_group}) {
    if (!group->empty() && group->size() != static_cast<size_t>(skeleton.num_bones()))
      return Fail(error, "scale_group and shift_group need one entry per bone (or none)");
  }
  if (!options.heading_priors.empty() && options.heading_priors.size() != imus.size())
    return Fail(error, "heading_priors needs one entry per IMU (or none)");
  if (!options.joint_sigmas.empty() &&
      options.joint_sigmas.size() != static_cast<size_t>(skeleton.num_bones()))
    return Fail(error, "joint_sigmas needs one entry per bone (or none)");
  for (const HeldPose& h : options.held_poses) {
    if (h.frame >= static_cast<int>(frames.size()) || h.theta.size() != skeleton.pose_dim())
      return Fail(error, "a held pose needs a frame of the window and a pose of the skeleton");
  }
  if (prior && prior->dof() != skeleton.pose_dim() - 6)
    return Fail(error, "the prior's dimension does not match the skeleton");
  return options.IsValid(error);
}

// A fixed Gaussian prior sum_i ((x_i - mean_i) / sigma_i)^2 on a block.
ceres::CostFunction* GaussianPrior(const double* mean, const Eigen::VectorXd& sigma) {
  ceres::Matrix a = sigma.cwiseInverse().asDiagonal();
  return new ceres::NormalPrior(a, Eigen::Map<const ceres::Vector>(mean, sigma.size()));
}

int NumGroups(const std::vector<int>& group) {
  return group.empty() ? 0 : std::max(0, 1 + *std::max_element(group.begin(), group.end()));
}

double MedianOf(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// The window's unknowns, each a Ceres parameter block (stable addresses: sized once).
struct Unknowns {
  std::vector<Eigen::VectorXd> thetas;
  std::vector<double> scales;           // per length group, relative
  std::vector<Eigen::Vector3d> shifts;  // per shift group, m
  std::vector<Eigen::Vector3d> sites;   // per keypoint, bone frame, m
  std::vector<Eigen::Vector3d> mounts;  // per IMU: m of M0 Exp(m)
  std::vector<double> headings;         // per IMU: psi of Rz(psi) R_ig0
};

// One measured orientation in the problem, for the report.
struct Reading {
  int frame, imu;
  Eigen::Matrix3d world;  // R_ig0 R_i
};

// The window's Ceres problem: the residuals borrow their cost functions from here.
class WindowProblem {
 public:
  WindowProblem(const Skeleton& skeleton, const Rig& rig, const KeypointLayout& layout,
                const std::vector<ImuSite>& imus, const std::optional<PosePrior>& prior,
                const CalibrationOptions& options, Unknowns* x)
      : skeleton_(skeleton),
        rig_(rig),
        layout_(layout),
        imus_(imus),
        options_(options),
        x_(x),
        problem_(Borrowing()),
        position_loss_(MakeLoss(options.terms.position)),
        orientation_loss_(MakeLoss(options.terms.orientation)) {
    const SolverOptions& terms = options.terms;
    if (prior && terms.pca_projection.enabled)
      projection_ = std::make_unique<PcaProjectionResidual>(*prior, terms.pca_projection.weight);
    if (prior && terms.pca_deviation.enabled)
      deviation_ = std::make_unique<PcaDeviationResidual>(*prior, terms.pca_deviation.weight);
    MakeJointPriors();
    keypoint_observations_.assign(layout.size(), 0);
  }

  // E_P, E_R, the joint conventions and the PCA terms of frame t.
  void AddFrame(const FrameObservations& frame, int t) {
    InputCounts counts;
    const CleanFrame clean = ValidateFrame(frame, rig_, layout_, imus_, options_.terms, &counts);
    double* theta = x_->thetas[t].data();
    if (options_.terms.position.enabled) AddKeypoints(clean, theta);
    if (options_.terms.orientation.enabled) AddOrientations(clean, t, theta);
    std::vector<double*> joints;
    for (int b = 1; b < skeleton_.num_bones(); ++b) {
      joints.push_back(theta + BlockOffset(b));
      if (joint_priors_[b])
        problem_.AddResidualBlock(joint_priors_[b].get(), nullptr, joints.back());
    }
    if (projection_) problem_.AddResidualBlock(projection_.get(), nullptr, joints);
    if (deviation_) problem_.AddResidualBlock(deviation_.get(), nullptr, joints);
  }

  // A held pose: each joint's rotation near the pose's.
  void AddHeldPose(const HeldPose& h) {
    double* theta = x_->thetas[h.frame].data();
    for (int b = 1; b < skeleton_.num_bones(); ++b) {
      const int at = BlockOffset(b);
      costs_.emplace_back(GaussianPrior(h.theta.data() + at, Eigen::Vector3d::Constant(h.sigma)));
      problem_.AddResidualBlock(costs_.back().get(), nullptr, theta + at);
    }
  }

  // The Gaussian priors on the sites, scales and shifts in the problem; held blocks.
  void AddParameterPriors(const std::vector<Eigen::Vector3d>& sites0) {
    for (size_t k = 0; k < x_->sites.size(); ++k)
      AddPrior(x_->sites[k].data(), sites0[k].data(),
               Eigen::Vector3d::Constant(options_.site_sigma), options_.estimate_sites);
    const double one = 1.0;
    for (double& s : x_->scales)
      AddPrior(&s, &one, Eigen::VectorXd::Constant(1, options_.scale_sigma),
               options_.estimate_scales);
    const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
    for (size_t v = 0; v < x_->shifts.size(); ++v) {
      const Eigen::Vector3d sigma = v < options_.shift_sigmas.size()
                                        ? options_.shift_sigmas[v]
                                        : Eigen::Vector3d::Constant(options_.shift_sigma);
      AddPrior(x_->shifts[v].data(), zero.data(), sigma, options_.estimate_shifts);
    }
    for (size_t i = 0; i < imus_.size(); ++i) {
      if (!problem_.HasParameterBlock(x_->mounts[i].data())) continue;
      if (!options_.estimate_mounts) problem_.SetParameterBlockConstant(x_->mounts[i].data());
      if (i < options_.heading_priors.size()) AddHeadingPrior(i, options_.heading_priors[i]);
      if (!options_.estimate_headings) problem_.SetParameterBlockConstant(&x_->headings[i]);
    }
  }

  ceres::Problem& problem() { return problem_; }
  const std::vector<Reading>& readings() const { return readings_; }
  const std::vector<int>& keypoint_observations() const { return keypoint_observations_; }

 private:
  static ceres::Problem::Options Borrowing() {
    ceres::Problem::Options o;
    o.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    o.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    return o;
  }

  // Per bone with a convention: its prior on the bone's local rotation.
  void MakeJointPriors() {
    joint_priors_.resize(skeleton_.num_bones());
    for (size_t b = 1; b < options_.joint_sigmas.size(); ++b) {
      std::vector<int> held;
      for (int k = 0; k < 3; ++k) {
        const double sigma = options_.joint_sigmas[b](k);
        if (sigma > 0 && std::isfinite(sigma)) held.push_back(k);
      }
      if (held.empty()) continue;
      ceres::Matrix a = ceres::Matrix::Zero(static_cast<int>(held.size()), 3);
      for (size_t r = 0; r < held.size(); ++r)
        a(r, held[r]) = 1.0 / options_.joint_sigmas[b](held[r]);
      joint_priors_[b] = std::make_unique<ceres::NormalPrior>(a, ceres::Vector::Zero(3));
    }
  }

  void AddKeypoints(const CleanFrame& clean, double* theta) {
    BodyPose start;
    ForwardKinematics(skeleton_, theta, &start);
    for (const Detection& d : clean.detections) {
      const int bone = layout_.sites[d.keypoint].bone;
      Eigen::Vector2d pixel;
      const Eigen::Vector3d x = start.position[bone] + start.rotation[bone] * x_->sites[d.keypoint];
      if (!rig_.cameras[d.camera].Project(x, &pixel)) continue;  // behind the camera at the start
      ScaledChain chain(&skeleton_, bone, options_.scale_group, options_.shift_group);
      std::vector<double*> blocks = ChainBlocks(skeleton_, bone, theta);
      blocks.push_back(x_->sites[d.keypoint].data());
      for (int g : chain.scale_groups()) blocks.push_back(&x_->scales[g]);
      for (int g : chain.shift_groups()) blocks.push_back(x_->shifts[g].data());
      costs_.emplace_back(new SiteReprojectionResidual(
          chain, &rig_.cameras[d.camera], d.pixel, d.confidence, options_.terms.position.weight));
      problem_.AddResidualBlock(costs_.back().get(), position_loss_.get(), blocks);
      ++keypoint_observations_[d.keypoint];
    }
  }

  void AddOrientations(const CleanFrame& clean, int t, double* theta) {
    for (size_t i = 0; i < imus_.size(); ++i) {
      if (!clean.imu_world[i]) continue;
      std::vector<double*> blocks = ChainBlocks(skeleton_, imus_[i].bone, theta);
      blocks.push_back(x_->mounts[i].data());
      blocks.push_back(&x_->headings[i]);
      costs_.emplace_back(new MountedOrientationResidual(ScaledChain(&skeleton_, imus_[i].bone, {}),
                                                         imus_[i].mount, *clean.imu_world[i],
                                                         options_.terms.orientation.weight));
      problem_.AddResidualBlock(costs_.back().get(), orientation_loss_.get(), blocks);
      readings_.push_back({t, static_cast<int>(i), *clean.imu_world[i]});
    }
  }

  // The prior's yaw as a turn psi of the given reference (wrapped to the nearest turn).
  void AddHeadingPrior(size_t i, const Eigen::Vector2d& prior) {
    const double sigma = prior(1);
    if (!(sigma > 0) || !std::isfinite(sigma)) return;
    const Eigen::Matrix3d& r = imus_[i].reference;
    const double mean = std::remainder(prior(0) - std::atan2(r(1, 0), r(0, 0)), 2 * M_PI);
    costs_.emplace_back(GaussianPrior(&mean, Eigen::VectorXd::Constant(1, sigma)));
    problem_.AddResidualBlock(costs_.back().get(), nullptr, &x_->headings[i]);
  }

  // A prior on a block that is in the problem, held when it is not estimated.
  void AddPrior(double* block, const double* mean, const Eigen::VectorXd& sigma, bool estimated) {
    if (!problem_.HasParameterBlock(block)) return;
    costs_.emplace_back(GaussianPrior(mean, sigma));
    problem_.AddResidualBlock(costs_.back().get(), nullptr, block);
    if (!estimated) problem_.SetParameterBlockConstant(block);
  }

  const Skeleton& skeleton_;
  const Rig& rig_;
  const KeypointLayout& layout_;
  const std::vector<ImuSite>& imus_;
  const CalibrationOptions& options_;
  Unknowns* x_;
  ceres::Problem problem_;
  std::unique_ptr<ceres::LossFunction> position_loss_, orientation_loss_;
  std::unique_ptr<ceres::CostFunction> projection_, deviation_;
  std::vector<std::unique_ptr<ceres::CostFunction>> joint_priors_, costs_;
  std::vector<Reading> readings_;
  std::vector<int> keypoint_observations_;
};

// The skeleton with the estimated offsets, as ScaledChain poses them (rest-pose differences).
bool AdjustedSkeleton(const Skeleton& skeleton, const CalibrationOptions& options,
                      const Unknowns& x, Skeleton* out, std::string* error) {
  std::vector<Skeleton::Bone> bones = skeleton.bones();
  const std::vector<double> rest_theta(skeleton.pose_dim(), 0.0);
  for (int b = 1; b < skeleton.num_bones(); ++b) {
    ScaledChain chain(&skeleton, b, options.scale_group, options.shift_group);
    std::vector<const double*> theta_blocks, scales, shifts;
    for (int j : chain.chain()) theta_blocks.push_back(rest_theta.data() + BlockOffset(j));
    for (int g : chain.scale_groups()) scales.push_back(&x.scales[g]);
    for (int g : chain.shift_groups()) shifts.push_back(x.shifts[g].data());
    BodyPose rest;
    chain.Pose(theta_blocks.data(), scales.data(), shifts.data(), &rest);
    bones[b].offset = rest.position[b] - rest.position[skeleton.bone(b).parent];
  }
  return Skeleton::Create(std::move(bones), out, error);
}

// Median angle (deg) per IMU between its calibrated reading and its solved sensor orientation.
std::vector<double> ImuResidualsDeg(const CalibrationResult& r, const Unknowns& x,
                                    const std::vector<Reading>& readings) {
  std::vector<std::vector<double>> angles(r.imus.size());
  BodyPose pose;
  int posed = -1;
  for (const Reading& reading : readings) {
    if (reading.frame != posed)
      ForwardKinematics(r.skeleton, r.thetas[reading.frame].data(), &pose);
    posed = reading.frame;
    const ImuSite& site = r.imus[reading.imu];
    const Eigen::Matrix3d measured =
        Exp(Eigen::Vector3d(0, 0, x.headings[reading.imu])) * reading.world;
    angles[reading.imu].push_back(AngleBetween(measured, pose.rotation[site.bone] * site.mount) *
                                  180 / M_PI);
  }
  std::vector<double> out;
  for (auto& a : angles) out.push_back(MedianOf(a));
  return out;
}

}  // namespace

bool CalibrationOptions::IsValid(std::string* error) const {
  internal::OptionChecks check;
  std::string messages;
  const bool terms_valid = terms.IsValid(&messages);
  check.Nested(terms_valid, "terms: " + messages);
  check.Expect(scale_sigma > 0.0, "scale_sigma", scale_sigma, "> 0");
  check.Expect(shift_sigma > 0.0, "shift_sigma", shift_sigma, "> 0 m");
  for (const Eigen::Vector3d& sigma : shift_sigmas)
    check.Expect((sigma.array() > 0).all() && sigma.allFinite(), "shift_sigmas", "finite, > 0 m");
  for (const Eigen::Vector3d& sigma : joint_sigmas)
    check.Expect(!sigma.hasNaN() && (sigma.array() >= 0).all(), "joint_sigmas", ">= 0 rad");
  for (const HeldPose& h : held_poses) {
    check.Expect(h.frame >= 0, "held_poses.frame", h.frame, ">= 0");
    check.Expect(h.theta.allFinite(), "held_poses.theta", "finite");
    check.Expect(h.sigma > 0.0, "held_poses.sigma", h.sigma, "> 0 rad");
  }
  for (const Eigen::Vector2d& h : heading_priors)
    check.Expect(std::isfinite(h(0)) && !std::isnan(h(1)), "heading_priors",
                 "a finite yaw and a sigma");
  check.Expect(site_sigma > 0.0, "site_sigma", site_sigma, "> 0 m");
  check.Expect(site_observable_std >= 0.0, "site_observable_std", site_observable_std, ">= 0 m");
  check.Expect(max_iterations >= 1, "max_iterations", max_iterations, ">= 1");
  check.Expect(num_threads >= 1, "num_threads", num_threads, ">= 1");
  return check.Done(error);
}

bool CalibrateWindow(const Skeleton& skeleton, const Rig& rig, const KeypointLayout& layout,
                     const std::vector<ImuSite>& imus, const std::optional<PosePrior>& prior,
                     const std::vector<FrameObservations>& frames,
                     const std::vector<Eigen::VectorXd>& thetas, const CalibrationOptions& options,
                     CalibrationResult* result, std::string* error) {
  if (!CheckInputs(skeleton, imus, frames, thetas, prior, options, error)) return false;
  Unknowns x{thetas,
             std::vector<double>(NumGroups(options.scale_group), 1.0),
             std::vector<Eigen::Vector3d>(NumGroups(options.shift_group), Eigen::Vector3d::Zero()),
             {},
             std::vector<Eigen::Vector3d>(imus.size(), Eigen::Vector3d::Zero()),
             std::vector<double>(imus.size(), 0.0)};
  for (const Site& s : layout.sites) x.sites.push_back(s.offset);
  const std::vector<Eigen::Vector3d> sites0 = x.sites;

  WindowProblem window(skeleton, rig, layout, imus, prior, options, &x);
  for (size_t t = 0; t < frames.size(); ++t) window.AddFrame(frames[t], static_cast<int>(t));
  for (const HeldPose& h : options.held_poses) window.AddHeldPose(h);
  if (window.problem().NumResidualBlocks() == 0)
    return Fail(error, "nothing in the calibration window could be used");
  window.AddParameterPriors(sites0);

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.num_threads = std::max(1, options.num_threads);
  solver_options.function_tolerance = 1e-7;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &window.problem(), &summary);
  result->initial_cost = 2.0 * summary.initial_cost;
  result->final_cost = 2.0 * summary.final_cost;
  result->iterations = static_cast<int>(summary.iterations.size()) - 1;
  result->converged = summary.termination_type == ceres::CONVERGENCE;
  result->message = summary.BriefReport();
  if (!summary.IsSolutionUsable()) return Fail(error, "calibration failed: " + summary.message);

  if (options.estimate_sites && options.site_observable_std > 0.0) {
    internal::KeepObservedSiteChanges(options.site_observable_std, sites0, &window.problem(),
                                      &x.sites, &result->site_directions_kept,
                                      &result->site_directions);
  }
  if (!AdjustedSkeleton(skeleton, options, x, &result->skeleton, error)) return false;
  result->thetas = x.thetas;
  result->scales = x.scales;
  result->shifts = x.shifts;
  result->keypoint_observations = window.keypoint_observations();
  result->layout = layout;
  for (int k = 0; k < layout.size(); ++k) result->layout.sites[k].offset = x.sites[k];
  result->imus = imus;
  for (size_t i = 0; i < imus.size(); ++i) {
    result->imus[i].mount = imus[i].mount * Exp(x.mounts[i]);
    result->imus[i].reference = Exp(Eigen::Vector3d(0, 0, x.headings[i])) * imus[i].reference;
  }
  result->imu_residual_deg = ImuResidualsDeg(*result, x, window.readings());
  return true;
}

}  // namespace mocap
