#include "frame_problem.h"

#include "mocap/residuals/acceleration_residual.h"
#include "mocap/residuals/motion_residual.h"
#include "mocap/residuals/orientation_residual.h"
#include "mocap/residuals/pca_prior_residuals.h"
#include "mocap/residuals/point_residual.h"
#include "mocap/residuals/position_residual.h"
#include "mocap/solver.h"

namespace mocap {

ceres::LossFunction* MakeLoss(const TermOptions& t) {
  switch (t.loss) {
    case LossType::kCauchy:
      return new ceres::CauchyLoss(t.loss_scale);
    case LossType::kHuber:
      return new ceres::HuberLoss(t.loss_scale);
    case LossType::kTrivial:
      return nullptr;
  }
  return nullptr;
}

FrameProblem::FrameProblem(const Skeleton& skeleton, double* theta)
    : skeleton_(skeleton),
      theta_(theta),
      fk_(&skeleton),
      problem_(skeleton.pose_dim()),
      chain_offsets_(skeleton.num_bones()) {
  for (int b = 0; b < skeleton.num_bones(); ++b) {
    for (int j : skeleton.Chain(b)) chain_offsets_[b].push_back(BlockOffset(j));
  }
}

ceres::LossFunction* FrameProblem::Loss(Term term, const TermOptions& options) {
  if (!losses_[term]) losses_[term].reset(MakeLoss(options));
  return losses_[term].get();
}

void FrameProblem::Add(Term term, const ceres::CostFunction* cost, const TermOptions& options,
                       const std::vector<int>& offsets, const Eigen::MatrixXd* gram) {
  const int block = problem_.AddResidualBlock(cost, Loss(term, options), offsets, gram);
  if (block >= 0) blocks_[term].push_back(block);  // (the chains' offsets always fit theta)
}

int FrameProblem::AddPositionTerms(const Rig& rig, const KeypointLayout& layout,
                                   const std::vector<Detection>& detections,
                                   const TermOptions& options) {
  BodyPose start;
  ForwardKinematics(skeleton_, theta_, &start);
  int behind = 0;
  for (const Detection& d : detections) {
    const Site& site = layout.sites[d.keypoint];
    const Camera& cam = rig.cameras[d.camera];
    Eigen::Vector2d pixel;
    if (!cam.Project(start.position[site.bone] + start.rotation[site.bone] * site.offset, &pixel)) {
      ++behind;
      continue;
    }
    auto* cost = new PositionResidual(&fk_, &cam, site, d.pixel, d.confidence, options.weight);
    owned_.emplace_back(cost);
    Add(kPositionTerm, cost, options, chain_offsets_[site.bone]);
  }
  return behind;
}

void FrameProblem::AddOrientationTerm(const ImuSite& site, const Eigen::Matrix3d& measured_world,
                                      const TermOptions& options) {
  auto* cost = new OrientationResidual(&fk_, site, measured_world, options.weight);
  owned_.emplace_back(cost);
  Add(kOrientationTerm, cost, options, chain_offsets_[site.bone]);
}

void FrameProblem::AddAccelerationTerm(const ImuSite& site, const Eigen::Vector3d& x1,
                                       const Eigen::Vector3d& x0, double h1, double h2,
                                       const Eigen::Vector3d& measured_world,
                                       const TermOptions& options) {
  auto* cost = new AccelerationResidual(&fk_, site, x1, x0, h1, h2, measured_world, options.weight);
  owned_.emplace_back(cost);
  Add(kAccelerationTerm, cost, options, chain_offsets_[site.bone]);
}

void FrameProblem::AddMotionTerm(const Site& site, const Eigen::Vector3d& x1,
                                 const Eigen::Vector3d& v, double h1, double h2,
                                 const TermOptions& options) {
  auto* cost = new MotionResidual(&fk_, site, x1, v, h1, h2, options.weight);
  owned_.emplace_back(cost);
  Add(kMotionTerm, cost, options, chain_offsets_[site.bone]);
}

void FrameProblem::AddPointTerm(const Site& site, const Eigen::Vector3d& target,
                                const TermOptions& options) {
  auto* cost = new PointResidual(&fk_, site, target, options.weight);
  owned_.emplace_back(cost);
  Add(kPointTerm, cost, options, chain_offsets_[site.bone]);
}

void FrameProblem::AddPriorTerm(Term term, const LinearPriorResidual* cost,
                                const TermOptions& options) {
  std::vector<int> joints;
  for (int b = 1; b < skeleton_.num_bones(); ++b) joints.push_back(BlockOffset(b));
  Add(term, cost, options, joints, &cost->gram());
}

LmSummary FrameProblem::Solve(const LmOptions& options) {
  return SolveLm(options, &problem_, theta_);
}

TermCosts FrameProblem::Costs() {
  const Eigen::Map<const Eigen::VectorXd> theta(theta_, skeleton_.pose_dim());
  // The solve leaves its solution's block costs behind; anything else is evaluated.
  if (problem_.costs_at().size() != theta.size() || problem_.costs_at() != theta) {
    problem_.EvaluateBlockCosts(theta_);
  }
  TermCosts costs;
  double* out[6] = {&costs.orientation,    &costs.position,      &costs.acceleration,
                    &costs.pca_projection, &costs.pca_deviation, &costs.motion};
  for (int t = 0; t < 6; ++t) {
    for (int i : blocks_[t]) *out[t] += problem_.block_cost(i);
  }
  return costs;
}

}  // namespace mocap
