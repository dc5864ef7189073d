// Step 4b of the window calibration: of the keypoint sites' estimated change, only what the
// window observes is kept (the directions its covariance pins down).
#ifndef MOCAP_SRC_OBSERVED_SITES_H_
#define MOCAP_SRC_OBSERVED_SITES_H_

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <vector>

namespace mocap::internal {

// Projects the sites' change from sites0 onto the eigenvectors of their marginal
// covariance whose standard deviation is below max_std; when the covariance cannot be had
// (a rank-deficient window), the sites stay at sites0.
void KeepObservedSiteChanges(double max_std, const std::vector<Eigen::Vector3d>& sites0,
                             ceres::Problem* problem, std::vector<Eigen::Vector3d>* sites,
                             int* kept, Eigen::MatrixXd* directions);

}  // namespace mocap::internal

#endif  // MOCAP_SRC_OBSERVED_SITES_H_
