#include "frame_problem.h"

#include "mocap/residuals/acceleration_residual.h"
#include "mocap/residuals/motion_residual.h"
#include "mocap/residuals/orientation_residual.h"
#include "mocap/residuals/point_residual.h"
#include "mocap/residuals/position_residual.h"
#include "mocap/solver.h"

namespace mocap {
namespace {

ceres::Problem::Options BorrowingProblem() {
  ceres::Problem::Options o;
  o.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  o.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  o.disable_all_safety_checks = true;  // the blocks are ours and consistent by construction
  return o;
}

}  // namespace

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
    : skeleton_(skeleton), theta_(theta), fk_(&skeleton), problem_(BorrowingProblem()) {
  for (int b = 0; b < skeleton.num_bones(); ++b) {
    problem_.AddParameterBlock(theta + BlockOffset(b), BlockSize(b));
  }
}

ceres::LossFunction* FrameProblem::Loss(Term term, const TermOptions& options) {
  if (!losses_[term]) losses_[term].reset(MakeLoss(options));
  return losses_[term].get();
}

void FrameProblem::Add(Term term, ceres::CostFunction* cost, const TermOptions& options,
                       const std::vector<double*>& blocks) {
  blocks_[term].push_back(problem_.AddResidualBlock(cost, Loss(term, options), blocks));
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
    Add(kPositionTerm, cost, options, ChainBlocks(skeleton_, site.bone, theta_));
  }
  return behind;
}

void FrameProblem::AddOrientationTerm(const ImuSite& site, const Eigen::Matrix3d& measured_world,
                                      const TermOptions& options) {
  auto* cost = new OrientationResidual(&fk_, site, measured_world, options.weight);
  owned_.emplace_back(cost);
  Add(kOrientationTerm, cost, options, ChainBlocks(skeleton_, site.bone, theta_));
}

void FrameProblem::AddAccelerationTerm(const ImuSite& site, const Eigen::Vector3d& x1,
                                       const Eigen::Vector3d& x0, double h1, double h2,
                                       const Eigen::Vector3d& measured_world,
                                       const TermOptions& options) {
  auto* cost = new AccelerationResidual(&fk_, site, x1, x0, h1, h2, measured_world, options.weight);
  owned_.emplace_back(cost);
  Add(kAccelerationTerm, cost, options, ChainBlocks(skeleton_, site.bone, theta_));
}

void FrameProblem::AddMotionTerm(const Site& site, const Eigen::Vector3d& x1,
                                 const Eigen::Vector3d& v, double h1, double h2,
                                 const TermOptions& options) {
  auto* cost = new MotionResidual(&fk_, site, x1, v, h1, h2, options.weight);
  owned_.emplace_back(cost);
  Add(kMotionTerm, cost, options, ChainBlocks(skeleton_, site.bone, theta_));
}

void FrameProblem::AddPointTerm(const Site& site, const Eigen::Vector3d& target,
                                const TermOptions& options) {
  auto* cost = new PointResidual(&fk_, site, target, options.weight);
  owned_.emplace_back(cost);
  Add(kPointTerm, cost, options, ChainBlocks(skeleton_, site.bone, theta_));
}

void FrameProblem::AddPriorTerm(Term term, ceres::CostFunction* cost, const TermOptions& options) {
  std::vector<double*> joints;
  for (int b = 1; b < skeleton_.num_bones(); ++b) joints.push_back(theta_ + BlockOffset(b));
  Add(term, cost, options, joints);
}

void FrameProblem::Solve(const ceres::Solver::Options& options, ceres::Solver::Summary* summary) {
  ceres::Solve(options, &problem_, summary);
}

TermCosts FrameProblem::Costs() {
  TermCosts costs;
  double* out[6] = {&costs.orientation,    &costs.position,      &costs.acceleration,
                    &costs.pca_projection, &costs.pca_deviation, &costs.motion};
  for (int t = 0; t < 6; ++t) {
    for (ceres::ResidualBlockId id : blocks_[t]) {
      double cost = 0.0;
      problem_.EvaluateResidualBlock(id, /*apply_loss_function=*/true, &cost, nullptr, nullptr);
      *out[t] += 2.0 * cost;  // Ceres reports rho / 2
    }
  }
  return costs;
}

}  // namespace mocap
