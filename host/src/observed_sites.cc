#include "observed_sites.h"

#include <Eigen/Eigenvalues>

namespace mocap::internal {

void KeepObservedSiteChanges(double max_std, const std::vector<Eigen::Vector3d>& sites0,
                             ceres::Problem* problem, std::vector<Eigen::Vector3d>* sites,
                             int* kept, Eigen::MatrixXd* directions) {
  std::vector<const double*> blocks;
  std::vector<int> keypoints;
  for (size_t k = 0; k < sites->size(); ++k) {
    if (problem->HasParameterBlock((*sites)[k].data())) {
      blocks.push_back((*sites)[k].data());
      keypoints.push_back(static_cast<int>(k));
    }
  }
  *kept = 0;
  *directions = Eigen::MatrixXd::Zero(3 * static_cast<int>(sites->size()), 0);
  if (blocks.empty()) return;
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::SPARSE_QR;
  co.num_threads = 2;
  ceres::Covariance covariance(co);
  const int n = 3 * static_cast<int>(blocks.size());
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> c(n, n);
  if (!covariance.Compute(blocks, problem) || !covariance.GetCovarianceMatrix(blocks, c.data())) {
    *sites = sites0;  // the window does not tell what it observes (rank-deficient): no change
    *kept = 0;
    return;
  }
  Eigen::VectorXd change(n);
  for (size_t j = 0; j < keypoints.size(); ++j) {
    change.segment<3>(3 * j) = (*sites)[keypoints[j]] - sites0[keypoints[j]];
  }
  const Eigen::MatrixXd dense = c;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(dense);
  const Eigen::VectorXd& variance = eig.eigenvalues();
  Eigen::VectorXd kept_change = Eigen::VectorXd::Zero(n);
  std::vector<int> columns;
  for (int i = 0; i < n; ++i) {
    if (variance(i) < max_std * max_std) {
      const Eigen::VectorXd v = eig.eigenvectors().col(i);
      kept_change += v * v.dot(change);
      columns.push_back(i);
    }
  }
  *kept = static_cast<int>(columns.size());
  directions->setZero(3 * static_cast<int>(sites->size()), *kept);
  for (int c = 0; c < *kept; ++c) {
    for (size_t j = 0; j < keypoints.size(); ++j)
      directions->block<3, 1>(3 * keypoints[j], c) =
          eig.eigenvectors().block(3 * j, columns[c], 3, 1);
  }
  for (size_t j = 0; j < keypoints.size(); ++j) {
    (*sites)[keypoints[j]] = sites0[keypoints[j]] + kept_change.segment<3>(3 * j);
  }
}

}  // namespace mocap::internal
