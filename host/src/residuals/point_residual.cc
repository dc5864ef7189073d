#include "mocap/residuals/point_residual.h"

#include <ceres/ceres.h>

#include <cmath>
#include <memory>

namespace mocap {

PointResidual::PointResidual(KinematicsCache* fk, const Site& site, const Eigen::Vector3d& target,
                             double weight)
    : fk_(fk), site_(site), target_(target), sqrt_weight_(std::sqrt(weight)) {
  set_num_residuals(3);
  *mutable_parameter_block_sizes() = ChainBlockSizes(fk->skeleton(), site.bone);
}

bool PointResidual::Evaluate(double const* const* parameters, double* residuals,
                             double** jacobians) const {
  const BodyPose& pose = fk_->Update(site_.bone, parameters);
  const Eigen::Vector3d x = pose.position[site_.bone] + pose.rotation[site_.bone] * site_.offset;
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = sqrt_weight_ * (x - target_);
  if (jacobians != nullptr) {
    const Eigen::Matrix3d m = sqrt_weight_ * Eigen::Matrix3d::Identity();
    PointJacobian<3>(fk_->skeleton(), pose, site_.bone, x, m, jacobians);
  }
  return true;
}

bool FitToPoints(const Skeleton& skeleton, const std::vector<Site>& sites,
                 const std::vector<Eigen::Vector3d>& targets, const std::vector<double>& weights,
                 int max_iterations, Eigen::VectorXd* theta) {
  if (theta->size() != skeleton.pose_dim() || sites.size() != targets.size() ||
      sites.size() != weights.size()) {
    return false;
  }
  KinematicsCache fk(&skeleton);
  ceres::Problem problem;
  for (int b = 0; b < skeleton.num_bones(); ++b) {
    problem.AddParameterBlock(theta->data() + BlockOffset(b), BlockSize(b));
  }
  int terms = 0;
  for (size_t i = 0; i < sites.size(); ++i) {
    if (!(weights[i] > 0.0) || !std::isfinite(weights[i]) || !targets[i].allFinite() ||
        sites[i].bone < 0 || sites[i].bone >= skeleton.num_bones()) {
      continue;
    }
    problem.AddResidualBlock(new PointResidual(&fk, sites[i], targets[i], weights[i]), nullptr,
                             ChainBlocks(skeleton, sites[i].bone, theta->data()));
    ++terms;
  }
  if (terms == 0) return false;
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  options.max_num_iterations = max_iterations;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  return summary.IsSolutionUsable() && theta->allFinite();
}

}  // namespace mocap
