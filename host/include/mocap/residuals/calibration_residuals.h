// The window calibration's residuals (window_calibration.h): E_P and E_R whose sites,
// bone lengths, mountings and headings are parameters too.
//
// Bone offsets: bone j's offset is s_u t_j + D_j d_v (ScaledChain). For a point x on bone
// b, with j running over Chain(b) except the root:
//   dx/ds_u = sum over j in length group u of G_parent(j) t_j
//   dx/dd_v = sum over j in shift group v of G_parent(j) D_j.
// Site: x = p_b + G_b o, so dx/do = G_b.
// Mounting M = M0 Exp(m): the solved sensor orientation S = G_b M moves by the right
// perturbation J_r(m) dm. Heading: the measured orientation A = Rz(psi) W turns about world
// z, and Log(A^T S) moves by -J_r^-1(r0) S^T z dpsi (derivation in the .cc).
// Parameter blocks: theta's blocks of Chain(b) (kinematics.h), then the extra blocks named
// by each constructor. Thread-safe (no shared cache).
#ifndef MOCAP_RESIDUALS_CALIBRATION_RESIDUALS_H_
#define MOCAP_RESIDUALS_CALIBRATION_RESIDUALS_H_

#include <ceres/cost_function.h>

#include <vector>

#include "mocap/camera.h"
#include "mocap/kinematics.h"
#include "mocap/skeleton.h"

namespace mocap {

// Bone b's chain posed with adjusted offsets: bone j's offset is s_u t_j + D_j d_v, with s_u
// the scale of its length group u (1 when it has none) and d_v the shift of its shift group v
// (0 when none); D_j = diag(1, -1, 1) when bone j lies on the other side (y) of its group's
// first bone, so a left/right pair shifts mirrored. The root's offset is never adjusted.
class ScaledChain {
 public:
  // scale_group / shift_group: per bone, -1 for none (either may be empty: none at all).
  ScaledChain(const Skeleton* skeleton, int bone, const std::vector<int>& scale_group,
              const std::vector<int>& shift_group = {});
  int bone() const { return bone_; }
  const Skeleton* skeleton() const { return skeleton_; }
  const std::vector<int>& chain() const { return chain_; }
  int num_scale_blocks() const { return static_cast<int>(scale_groups_.size()); }
  int num_shift_blocks() const { return static_cast<int>(shift_groups_.size()); }
  // Groups of the scale blocks (size 1) and of the shift blocks (size 3), in block order.
  const std::vector<int>& scale_groups() const { return scale_groups_; }
  const std::vector<int>& shift_groups() const { return shift_groups_; }
  // Poses the chain from its theta blocks, the scale blocks and the shift blocks (either
  // null when the chain has none).
  void Pose(double const* const* theta_blocks, const double* const* scales,
            const double* const* shifts, BodyPose* pose) const;
  // jacobians[u] (Rows x 1) = m * dx/ds_u, then jacobians[num_scale_blocks + v] (Rows x 3,
  // row-major) = m * dx/dd_v, for the point x on the chain's bone.
  template <int Rows>
  void OffsetJacobians(const BodyPose& pose, const Eigen::Matrix<double, Rows, 3>& m,
                       double** jacobians) const {
    for (size_t u = 0; u < scale_groups_.size(); ++u) {
      if (jacobians[u] == nullptr) continue;
      Eigen::Vector3d d = Eigen::Vector3d::Zero();
      for (size_t i = 0; i + 1 < chain_.size(); ++i) {
        if (scale_block_[i] != static_cast<int>(u)) continue;
        const int j = chain_[i];
        d += pose.rotation[skeleton_->bone(j).parent] * skeleton_->bone(j).offset;
      }
      Eigen::Map<Eigen::Matrix<double, Rows, 1>> out(jacobians[u]);
      out = m * d;
    }
    for (size_t v = 0; v < shift_groups_.size(); ++v) {
      double* block = jacobians[scale_groups_.size() + v];
      if (block == nullptr) continue;
      Eigen::Matrix3d d = Eigen::Matrix3d::Zero();
      for (size_t i = 0; i + 1 < chain_.size(); ++i) {
        if (shift_block_[i] != static_cast<int>(v)) continue;
        d += pose.rotation[skeleton_->bone(chain_[i]).parent] * Mirror(i);
      }
      Eigen::Map<Eigen::Matrix<double, Rows, 3, Eigen::RowMajor>> out(block);
      out = m * d;
    }
  }

 private:
  Eigen::Matrix3d Mirror(size_t i) const {
    return Eigen::Vector3d(1.0, mirror_[i], 1.0).asDiagonal();
  }
  const Skeleton* skeleton_;
  int bone_;
  std::vector<int> chain_, scale_block_, shift_block_, scale_groups_, shift_groups_;
  std::vector<double> mirror_;  // per chain bone: -1 when its shift is mirrored in y
};

// E_P of one detection: blocks chain, site offset (3), scale blocks (1 each), shift blocks (3
// each).
class SiteReprojectionResidual : public ceres::CostFunction {
 public:
  SiteReprojectionResidual(ScaledChain chain, const Camera* camera,
                           const Eigen::Vector2d& detection, double confidence, double weight);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  ScaledChain chain_;
  const Camera* camera_;
  Eigen::Vector2d detection_;
  double sqrt_weight_;
};

// E_R of one reading: blocks chain (offsets do not enter), mounting delta m (3), heading psi (1).
// measured_world: W = R_ig0 R_i; mount0: M0.
class MountedOrientationResidual : public ceres::CostFunction {
 public:
  MountedOrientationResidual(ScaledChain chain, const Eigen::Matrix3d& mount0,
                             const Eigen::Matrix3d& measured_world, double weight);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  ScaledChain chain_;
  Eigen::Matrix3d mount0_, measured_world_;
  double sqrt_weight_;
};

}  // namespace mocap

#endif  // MOCAP_RESIDUALS_CALIBRATION_RESIDUALS_H_
