// PCA pose prior over the non-root DOF (theta[6:], 60-D for the default skeleton).
//
// mean mu (d), basis M (d x k, orthonormal columns), sigma (k): the standard deviation
// of the training poses along each column of M (slide "Pose prior terms").
#ifndef MOCAP_PRIOR_H_
#define MOCAP_PRIOR_H_

#include <Eigen/Core>
#include <string>

namespace mocap {

struct PosePrior {
  Eigen::VectorXd mean;
  Eigen::MatrixXd basis;
  Eigen::VectorXd sigma;

  int dof() const { return static_cast<int>(mean.size()); }
  int rank() const { return static_cast<int>(basis.cols()); }
  // Sizes agree, basis columns are orthonormal (1e-6), sigma positive, all finite.
  bool IsValid(std::string* error) const;
};

// Prior file: {"format": "mocap.prior/1", "dof": d, "mean": [d numbers],
//   "basis": [k arrays of d numbers, one per component], "sigma": [k numbers]},
// 0 < k <= d <= kMaxPriorDof (a pose has 66), so a file allocates at most 8 MiB.
inline constexpr int kMaxPriorDof = 1024;
bool LoadPosePriorJson(const std::string& path, PosePrior* out, std::string* error);
bool ParsePosePriorJson(const std::string& text, PosePrior* out, std::string* error);
std::string PosePriorToJson(const PosePrior& prior);

}  // namespace mocap

#endif  // MOCAP_PRIOR_H_
