// Forward kinematics with analytic derivatives.
//
// For a world point x rigidly attached to bone b, and any bone j on b's chain
// (b and its ancestors), with p_j the joint pivot (bone j's origin):
//   dx / d(root translation) = I
//   dx / d(theta_j)          = -[x - p_j]_x * A_j,   A_j = G_j * RightJacobian(theta_j)
// and the world orientation G_b moves by the left perturbation
//   G_b <- Exp(A_j d theta_j) * G_b.
// A_j ("axes") is the world-frame image of a change of theta_j, computed once per pose.
//
// Parameter blocks: the solver gives Ceres one block per bone, each a segment of theta:
// the root's block is theta[0:6] (translation, rotation), bone b's is theta[3+3b : 6+3b].
// A residual on bone b takes the blocks of Chain(b) (b first, root last), so its
// Jacobian holds only the columns that can be non-zero.
#ifndef MOCAP_KINEMATICS_H_
#define MOCAP_KINEMATICS_H_

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "mocap/skeleton.h"

namespace mocap {

struct BodyPose {
  std::vector<Eigen::Matrix3d> rotation;  // G_b: bone -> world
  std::vector<Eigen::Vector3d> position;  // p_b: bone origin in world, metres
  std::vector<Eigen::Matrix3d> axes;      // A_b, see above
};

void ForwardKinematics(const Skeleton& skeleton, const double* theta, BodyPose* out);

// Parameter block of bone b inside theta, and its size.
inline int BlockOffset(int b) { return b == 0 ? 0 : Skeleton::RotationIndex(b); }
inline int BlockSize(int b) { return b == 0 ? 6 : 3; }
// Pointers to the blocks of Chain(b) inside theta, in chain order.
std::vector<double*> ChainBlocks(const Skeleton& skeleton, int b, double* theta);
std::vector<int> ChainBlockSizes(const Skeleton& skeleton, int b);

// jacobians[i] (Rows x BlockSize(chain[i]), row-major) = m * dx/d(block i) for the point
// x on bone b; null entries are skipped.
template <int Rows>
void PointJacobian(const Skeleton& skeleton, const BodyPose& pose, int b, const Eigen::Vector3d& x,
                   const Eigen::Matrix<double, Rows, 3>& m, double** jacobians) {
  using Out = Eigen::Map<Eigen::Matrix<double, Rows, 3, Eigen::RowMajor>, 0, Eigen::OuterStride<>>;
  const std::vector<int>& chain = skeleton.Chain(b);
  for (size_t i = 0; i < chain.size(); ++i) {
    if (jacobians[i] == nullptr) continue;
    const int j = chain[i];
    const int stride = BlockSize(j);
    double* rot = jacobians[i] + (j == 0 ? 3 : 0);
    if (j == 0) Out(jacobians[i], Rows, 3, Eigen::OuterStride<>(stride)) = m;
    const Eigen::Vector3d r = x - pose.position[j];
    // m * (-[r]_x), row by row: row_k * (-[r]_x) = (r x row_k^T)^T.
    Eigen::Matrix<double, Rows, 3> mr;
    for (int k = 0; k < Rows; ++k) mr.row(k) = r.cross(m.row(k).transpose()).transpose();
    Out(rot, Rows, 3, Eigen::OuterStride<>(stride)) = mr * pose.axes[j];
  }
}

// jacobians[i] = m * dphi/d(block i), dphi the world-frame left perturbation of bone b's
// orientation.
template <int Rows>
void RotationJacobian(const Skeleton& skeleton, const BodyPose& pose, int b,
                      const Eigen::Matrix<double, Rows, 3>& m, double** jacobians) {
  using Out = Eigen::Map<Eigen::Matrix<double, Rows, 3, Eigen::RowMajor>, 0, Eigen::OuterStride<>>;
  const std::vector<int>& chain = skeleton.Chain(b);
  for (size_t i = 0; i < chain.size(); ++i) {
    if (jacobians[i] == nullptr) continue;
    const int j = chain[i];
    const int stride = BlockSize(j);
    if (j == 0) Out(jacobians[i], Rows, 3, Eigen::OuterStride<>(stride)).setZero();
    Out(jacobians[i] + (j == 0 ? 3 : 0), Rows, 3, Eigen::OuterStride<>(stride)) = m * pose.axes[j];
  }
}

// Forward kinematics shared by every residual of one solve and updated lazily per bone:
// a bone is recomputed only when its parameters, or its parent, changed since it was
// last computed. Ceres evaluates all residuals at one point before moving to the next,
// so each bone is computed about once per evaluation. Not thread-safe.
class KinematicsCache {
 public:
  explicit KinematicsCache(const Skeleton* skeleton);
  // Brings Chain(b) up to date for the given chain blocks (chain order); returns the pose,
  // valid on that chain.
  const BodyPose& Update(int b, double const* const* chain_blocks);
  const Skeleton& skeleton() const { return *skeleton_; }

 private:
  const Skeleton* skeleton_;
  BodyPose pose_;
  std::vector<Eigen::Matrix<double, 6, 1>> key_;  // parameters each bone was computed from
  std::vector<uint64_t> version_, parent_version_;
  uint64_t next_version_ = 1;
};

}  // namespace mocap

#endif  // MOCAP_KINEMATICS_H_
