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

namespace mocap {
namespace {

bool Fail(std::string* error, const std::string& message) {
  if (error != nullptr) *error = message;
  return false;
}

bool CheckInputs(const Skeleton& skeleton, const std::vector<FrameObservations>& frames,
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
  if (!(options.scale_sigma > 0) || !(options.shift_sigma > 0) || !(options.site_sigma > 0) ||
      options.max_iterations < 1)
    return Fail(error, "the priors' sigmas must be positive, max_iterations at least 1");
  if (!options.joint_sigmas.empty() &&
      options.joint_sigmas.size() != static_cast<size_t>(skeleton.num_bones()))
    return Fail(error, "joint_sigmas needs one entry per bone (or none)");
  for (const Eigen::Vector3d& sigma : options.shift_sigmas) {
    if (!(sigma.array() > 0).all() || !sigma.allFinite())
      return Fail(error, "shift_sigmas must be positive");
  }
  if (prior && prior->dof() != skeleton.pose_dim() - 6)
    return Fail(error, "the prior's dimension does not match the skeleton");
  return options.terms.IsValid(error);
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

}  // namespace

bool CalibrateWindow(const Skeleton& skeleton, const Rig& rig, const KeypointLayout& layout,
                     const std::vector<ImuSite>& imus, const std::optional<PosePrior>& prior,
                     const std::vector<FrameObservations>& frames,
                     const std::vector<Eigen::VectorXd>& thetas, const CalibrationOptions& options,
                     CalibrationResult* result, std::string* error) {
  if (!CheckInputs(skeleton, frames, thetas, prior, options, error)) return false;
  const SolverOptions& terms = options.terms;
  const int groups = NumGroups(options.scale_group), shift_groups = NumGroups(options.shift_group);
  std::vector<double> scales(groups, 1.0);
  std::vector<Eigen::Vector3d> shifts(shift_groups, Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> sites, sites0;
  for (const Site& s : layout.sites) sites.push_back(s.offset);
  sites0 = sites;
  std::vector<Eigen::Vector3d> mounts(imus.size(), Eigen::Vector3d::Zero());
  std::vector<double> headings(imus.size(), 0.0);
  result->thetas = thetas;
  result->keypoint_observations.assign(layout.size(), 0);

  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  std::vector<std::unique_ptr<ceres::CostFunction>> costs;
  std::unique_ptr<ceres::LossFunction> position_loss(MakeLoss(terms.position)),
      orientation_loss(MakeLoss(terms.orientation));
  std::unique_ptr<ceres::CostFunction> projection, deviation;
  if (prior && terms.pca_projection.enabled)
    projection = std::make_unique<PcaProjectionResidual>(*prior, terms.pca_projection.weight);
  if (prior && terms.pca_deviation.enabled)
    deviation = std::make_unique<PcaDeviationResidual>(*prior, terms.pca_deviation.weight);
  const std::vector<int> no_groups;
  // Per bone: the joint convention's prior on its local rotation (null: none).
  std::vector<std::unique_ptr<ceres::CostFunction>> joint_priors(skeleton.num_bones());
  for (size_t b = 1; b < options.joint_sigmas.size(); ++b) {
    std::vector<int> held;
    for (int k = 0; k < 3; ++k) {
      const double sigma = options.joint_sigmas[b](k);
      if (sigma > 0 && std::isfinite(sigma)) held.push_back(k);
    }
    if (held.empty()) continue;
    ceres::Matrix a = ceres::Matrix::Zero(static_cast<int>(held.size()), 3);
    for (size_t r = 0; r < held.size(); ++r) a(r, held[r]) = 1.0 / options.joint_sigmas[b](held[r]);
    joint_priors[b] = std::make_unique<ceres::NormalPrior>(a, ceres::Vector::Zero(3));
  }
  // (frame, imu) of each orientation residual, for the report.
  std::vector<std::pair<int, int>> readings;
  std::vector<Eigen::Matrix3d> reading_world;

  for (size_t t = 0; t < frames.size(); ++t) {
    InputCounts counts;
    const CleanFrame clean = ValidateFrame(frames[t], rig, layout, imus, terms, &counts);
    double* theta = result->thetas[t].data();
    BodyPose start;
    ForwardKinematics(skeleton, theta, &start);
    if (terms.position.enabled) {
      for (const Detection& d : clean.detections) {
        const int bone = layout.sites[d.keypoint].bone;
        const Eigen::Vector3d x = start.position[bone] + start.rotation[bone] * sites[d.keypoint];
        Eigen::Vector2d pixel;
        if (!rig.cameras[d.camera].Project(x, &pixel)) continue;
        ScaledChain chain(&skeleton, bone, options.scale_group, options.shift_group);
        std::vector<double*> blocks = ChainBlocks(skeleton, bone, theta);
        blocks.push_back(sites[d.keypoint].data());
        for (int g : chain.scale_groups()) blocks.push_back(&scales[g]);
        for (int g : chain.shift_groups()) blocks.push_back(shifts[g].data());
        costs.emplace_back(new SiteReprojectionResidual(chain, &rig.cameras[d.camera], d.pixel,
                                                        d.confidence, terms.position.weight));
        problem.AddResidualBlock(costs.back().get(), position_loss.get(), blocks);
        ++result->keypoint_observations[d.keypoint];
      }
    }
    if (terms.orientation.enabled) {
      for (size_t i = 0; i < imus.size(); ++i) {
        if (!clean.imu_world[i]) continue;
        std::vector<double*> blocks = ChainBlocks(skeleton, imus[i].bone, theta);
        blocks.push_back(mounts[i].data());
        blocks.push_back(&headings[i]);
        costs.emplace_back(new MountedOrientationResidual(
            ScaledChain(&skeleton, imus[i].bone, no_groups), imus[i].mount, *clean.imu_world[i],
            terms.orientation.weight));
        problem.AddResidualBlock(costs.back().get(), orientation_loss.get(), blocks);
        readings.emplace_back(static_cast<int>(t), static_cast<int>(i));
        reading_world.push_back(*clean.imu_world[i]);
      }
    }
    std::vector<double*> joints;
    for (int b = 1; b < skeleton.num_bones(); ++b) joints.push_back(theta + BlockOffset(b));
    for (int b = 1; b < skeleton.num_bones(); ++b) {
      if (joint_priors[b])
        problem.AddResidualBlock(joint_priors[b].get(), nullptr, theta + BlockOffset(b));
    }
    if (projection) problem.AddResidualBlock(projection.get(), nullptr, joints);
    if (deviation) problem.AddResidualBlock(deviation.get(), nullptr, joints);
  }
  if (problem.NumResidualBlocks() == 0)
    return Fail(error, "nothing in the calibration window could be used");

  for (int k = 0; k < layout.size(); ++k) {
    if (!problem.HasParameterBlock(sites[k].data())) continue;
    costs.emplace_back(
        GaussianPrior(sites0[k].data(), Eigen::Vector3d::Constant(options.site_sigma)));
    problem.AddResidualBlock(costs.back().get(), nullptr, sites[k].data());
    if (!options.estimate_sites) problem.SetParameterBlockConstant(sites[k].data());
  }
  const double one = 1.0;
  for (double& s : scales) {
    if (!problem.HasParameterBlock(&s)) continue;
    costs.emplace_back(GaussianPrior(&one, Eigen::VectorXd::Constant(1, options.scale_sigma)));
    problem.AddResidualBlock(costs.back().get(), nullptr, &s);
    if (!options.estimate_scales) problem.SetParameterBlockConstant(&s);
  }
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  for (size_t v = 0; v < shifts.size(); ++v) {
    Eigen::Vector3d& d = shifts[v];
    if (!problem.HasParameterBlock(d.data())) continue;
    const Eigen::Vector3d sigma = v < options.shift_sigmas.size()
                                      ? options.shift_sigmas[v]
                                      : Eigen::Vector3d::Constant(options.shift_sigma);
    costs.emplace_back(GaussianPrior(zero.data(), sigma));
    problem.AddResidualBlock(costs.back().get(), nullptr, d.data());
    if (!options.estimate_shifts) problem.SetParameterBlockConstant(d.data());
  }
  for (size_t i = 0; i < imus.size(); ++i) {
    if (!problem.HasParameterBlock(mounts[i].data())) continue;
    if (!options.estimate_mounts) problem.SetParameterBlockConstant(mounts[i].data());
    if (!options.estimate_headings) problem.SetParameterBlockConstant(&headings[i]);
  }

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.num_threads = std::max(1, options.num_threads);
  solver_options.function_tolerance = 1e-7;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  result->initial_cost = 2.0 * summary.initial_cost;
  result->final_cost = 2.0 * summary.final_cost;
  result->iterations = static_cast<int>(summary.iterations.size()) - 1;
  result->converged = summary.termination_type == ceres::CONVERGENCE;
  result->message = summary.BriefReport();
  if (!summary.IsSolutionUsable()) return Fail(error, "calibration failed: " + summary.message);

  std::vector<Skeleton::Bone> bones = skeleton.bones();
  for (int b = 1; b < skeleton.num_bones(); ++b) {
    // The offset as ScaledChain poses it: the rest pose's difference of bone origins.
    ScaledChain one(&skeleton, b, options.scale_group, options.shift_group);
    BodyPose rest;
    std::vector<double> zeros(skeleton.pose_dim(), 0.0);
    std::vector<const double*> theta_blocks, scale_ptrs, shift_ptrs;
    for (int j : one.chain()) theta_blocks.push_back(zeros.data() + BlockOffset(j));
    for (int g : one.scale_groups()) scale_ptrs.push_back(&scales[g]);
    for (int g : one.shift_groups()) shift_ptrs.push_back(shifts[g].data());
    one.Pose(theta_blocks.data(), scale_ptrs.data(), shift_ptrs.data(), &rest);
    bones[b].offset = rest.position[b] - rest.position[skeleton.bone(b).parent];
  }
  if (!Skeleton::Create(std::move(bones), &result->skeleton, error)) return false;
  result->scales = scales;
  result->shifts = shifts;
  result->layout = layout;
  for (int k = 0; k < layout.size(); ++k) result->layout.sites[k].offset = sites[k];
  result->imus = imus;
  for (size_t i = 0; i < imus.size(); ++i) {
    result->imus[i].mount = imus[i].mount * Exp(mounts[i]);
    result->imus[i].reference = Exp(Eigen::Vector3d(0, 0, headings[i])) * imus[i].reference;
  }
  std::vector<std::vector<double>> angles(imus.size());
  BodyPose pose;
  int last_frame = -1;
  for (size_t r = 0; r < readings.size(); ++r) {
    const auto [t, i] = readings[r];
    if (t != last_frame) ForwardKinematics(result->skeleton, result->thetas[t].data(), &pose);
    last_frame = t;
    const Eigen::Matrix3d measured = Exp(Eigen::Vector3d(0, 0, headings[i])) * reading_world[r];
    const int b = imus[i].bone;
    angles[i].push_back(AngleBetween(measured, pose.rotation[b] * result->imus[i].mount) * 180 /
                        M_PI);
  }
  result->imu_residual_deg.clear();
  for (auto& a : angles) result->imu_residual_deg.push_back(MedianOf(a));
  return true;
}

}  // namespace mocap
