#include "frame_problem.h"

#include <algorithm>

#include "mocap/ground.h"
#include "mocap/residuals/acceleration_residual.h"
#include "mocap/residuals/ground_residual.h"
#include "mocap/residuals/motion_residual.h"
#include "mocap/residuals/orientation_residual.h"
#include "mocap/residuals/pca_prior_residuals.h"
#include "mocap/residuals/point_residual.h"
#include "mocap/residuals/position_residual.h"
#include "mocap/residuals/prediction_shift.h"
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

namespace {

// rho'(s) of a loss (null: trivial, 1), at least 0.
double LossSlope(const ceres::LossFunction* loss, double s) {
  double rho[3] = {s, 1.0, 0.0};
  if (loss != nullptr) loss->Evaluate(s, rho);
  return std::max(rho[1], 0.0);
}

}  // namespace

Eigen::Matrix3d RootPositionInformation(const Skeleton& skeleton, const double* theta,
                                        const Rig& rig, const KeypointLayout& layout,
                                        const std::vector<Detection>& detections,
                                        const TermOptions& position, const GroundContact& ground) {
  BodyPose pose;
  ForwardKinematics(skeleton, theta, &pose);
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
  const std::unique_ptr<ceres::LossFunction> position_loss(MakeLoss(position));
  // A keypoint's residual moves with the root's position as its site does: sqrt(w) dpi/dx.
  for (const Detection& d : detections) {
    const Site& site = layout.sites[d.keypoint];
    Eigen::Vector2d pixel;
    Eigen::Matrix<double, 2, 3> d_pixel;
    if (!rig.cameras[d.camera].Project(
            pose.position[site.bone] + pose.rotation[site.bone] * site.offset, &pixel, &d_pixel))
      continue;  // left out of the solve
    const double w = position.weight * d.confidence;
    information += LossSlope(position_loss.get(), w * (pixel - d.pixel).squaredNorm()) * w *
                   d_pixel.transpose() * d_pixel;
  }
  // E_G's residual moves with the root's height: sqrt(lambda_G) e_z.
  const int lowest = ground.contacts != nullptr ? LowestSite(pose, *ground.contacts) : -1;
  if (lowest >= 0) {
    const Site& c = (*ground.contacts)[lowest];
    const double height =
        (pose.position[c.bone] + pose.rotation[c.bone] * c.offset).z() - ground.floor;
    const std::unique_ptr<ceres::LossFunction> loss(MakeLoss(ground.options));
    information(2, 2) +=
        LossSlope(loss.get(), ground.options.weight * height * height) * ground.options.weight;
  }
  return information;
}

FrameProblem::FrameProblem(const Skeleton& skeleton, double* theta, bool shift_prediction)
    : skeleton_(skeleton),
      theta_(theta),
      x_(Eigen::VectorXd::Zero(skeleton.pose_dim() + (shift_prediction ? 3 : 0))),
      shift_offset_(shift_prediction ? skeleton.pose_dim() : -1),
      fk_(&skeleton),
      problem_(static_cast<int>(x_.size())),
      chain_offsets_(skeleton.num_bones()) {
  x_.head(skeleton.pose_dim()) = Eigen::Map<const Eigen::VectorXd>(theta, skeleton.pose_dim());
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
  ForwardKinematics(skeleton_, x_.data(), &start);
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
  auto cost = std::make_unique<AccelerationResidual>(&fk_, site, x1, x0, h1, h2, measured_world,
                                                     options.weight);
  const double scale = cost->position_scale();
  AddMotion(kAccelerationTerm, std::move(cost), scale, site.bone, options);
}

void FrameProblem::AddMotionTerm(const Site& site, const Eigen::Vector3d& x1,
                                 const Eigen::Vector3d& v, double h1, double h2,
                                 const TermOptions& options) {
  auto cost = std::make_unique<MotionResidual>(&fk_, site, x1, v, h1, h2, options.weight);
  const double scale = cost->position_scale();
  AddMotion(kMotionTerm, std::move(cost), scale, site.bone, options);
}

void FrameProblem::AddMotion(Term term, std::unique_ptr<ceres::CostFunction> cost,
                             double position_scale, int bone, const TermOptions& options) {
  std::vector<int> offsets = chain_offsets_[bone];
  if (shift_offset_ >= 0) {
    cost = std::make_unique<ShiftedPrediction>(std::move(cost), position_scale);
    offsets.push_back(shift_offset_);
    motion_information_ += position_scale * position_scale;
  }
  Add(term, cost.get(), options, offsets);
  owned_.push_back(std::move(cost));
}

void FrameProblem::AddGroundTerm(const std::vector<Site>& contacts, double floor,
                                 const TermOptions& options) {
  BodyPose start;
  ForwardKinematics(skeleton_, x_.data(), &start);
  const int lowest = LowestSite(start, contacts);
  if (lowest < 0) return;
  auto* cost = new GroundResidual(&fk_, contacts[lowest], floor, options.weight);
  owned_.emplace_back(cost);
  Add(kGroundTerm, cost, options, chain_offsets_[contacts[lowest].bone]);
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

void FrameProblem::AddPredictionShiftPrior(const Eigen::Matrix3d& h, double slack,
                                           double observed_ratio, double max_shift) {
  if (shift_offset_ < 0) return;
  Eigen::Matrix3d information = h / slack + Eigen::Matrix3d::Identity() / (max_shift * max_shift);
  if (motion_information_ > 0.0)
    information += h * h / (slack * observed_ratio * motion_information_);
  auto cost = std::make_unique<PredictionShiftPrior>(information);
  Add(kShiftTerm, cost.get(), TermOptions{true, 1.0, LossType::kTrivial, 1.0}, {shift_offset_});
  owned_.push_back(std::move(cost));
}

LmSummary FrameProblem::Solve(const LmOptions& options) {
  const LmSummary summary = SolveLm(options, &problem_, x_.data());
  Eigen::Map<Eigen::VectorXd>(theta_, skeleton_.pose_dim()) = x_.head(skeleton_.pose_dim());
  return summary;
}

TermCosts FrameProblem::Costs() {
  // The solve leaves its solution's block costs behind; anything else is evaluated.
  if (problem_.costs_at().size() != x_.size() || problem_.costs_at() != x_) {
    problem_.EvaluateBlockCosts(x_.data());
  }
  TermCosts costs;
  double* out[7] = {&costs.orientation,    &costs.position,      &costs.acceleration,
                    &costs.pca_projection, &costs.pca_deviation, &costs.motion,
                    &costs.ground};
  for (int t = 0; t < 7; ++t) {
    for (int i : blocks_[t]) *out[t] += problem_.block_cost(i);
  }
  return costs;
}

}  // namespace mocap
