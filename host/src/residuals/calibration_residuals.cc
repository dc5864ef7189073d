#include "mocap/residuals/calibration_residuals.h"

#include <algorithm>
#include <cmath>

#include "mocap/so3.h"

namespace mocap {

namespace {

// Index of group g in groups (appended when new); -1 for g < 0.
int BlockOf(int g, std::vector<int>* groups) {
  if (g < 0) return -1;
  auto it = std::find(groups->begin(), groups->end(), g);
  if (it == groups->end()) it = groups->insert(groups->end(), g);
  return static_cast<int>(it - groups->begin());
}

int GroupOf(const std::vector<int>& group, int bone) {
  return bone == 0 || bone >= static_cast<int>(group.size()) ? -1 : group[bone];
}

}  // namespace

ScaledChain::ScaledChain(const Skeleton* skeleton, int bone, const std::vector<int>& scale_group,
                         const std::vector<int>& shift_group)
    : skeleton_(skeleton), bone_(bone), chain_(skeleton->Chain(bone)) {
  for (int j : chain_) {
    scale_block_.push_back(BlockOf(GroupOf(scale_group, j), &scale_groups_));
    const int g = GroupOf(shift_group, j);
    shift_block_.push_back(BlockOf(g, &shift_groups_));
    double mirror = 1.0;
    if (g >= 0) {
      const int first = static_cast<int>(std::find(shift_group.begin(), shift_group.end(), g) -
                                         shift_group.begin());
      if (skeleton->bone(first).offset.y() * skeleton->bone(j).offset.y() < 0) mirror = -1.0;
    }
    mirror_.push_back(mirror);
  }
}

void ScaledChain::Pose(double const* const* theta_blocks, const double* const* scales,
                       const double* const* shifts, BodyPose* pose) const {
  const int n = skeleton_->num_bones();
  pose->rotation.resize(n);
  pose->position.resize(n);
  pose->axes.resize(n);
  for (int i = static_cast<int>(chain_.size()) - 1; i >= 0; --i) {  // root first
    const int j = chain_[i];
    const double* block = theta_blocks[i];
    const Eigen::Map<const Eigen::Vector3d> w(j == 0 ? block + 3 : block);
    const Eigen::Matrix3d local = Exp(w);
    const int parent = skeleton_->bone(j).parent;
    if (parent < 0) {
      pose->rotation[j] = local;
      pose->position[j] = Eigen::Map<const Eigen::Vector3d>(block) + skeleton_->bone(j).offset;
    } else {
      Eigen::Vector3d offset = skeleton_->bone(j).offset;
      if (scale_block_[i] >= 0) offset *= *scales[scale_block_[i]];
      if (shift_block_[i] >= 0)
        offset += Mirror(i) * Eigen::Map<const Eigen::Vector3d>(shifts[shift_block_[i]]);
      pose->rotation[j] = pose->rotation[parent] * local;
      pose->position[j] = pose->position[parent] + pose->rotation[parent] * offset;
    }
    pose->axes[j] = pose->rotation[j] * RightJacobian(w);
  }
}

SiteReprojectionResidual::SiteReprojectionResidual(ScaledChain chain, const Camera* camera,
                                                   const Eigen::Vector2d& detection,
                                                   double confidence, double weight)
    : chain_(std::move(chain)),
      camera_(camera),
      detection_(detection),
      sqrt_weight_(std::sqrt(weight * confidence)) {
  set_num_residuals(2);
  std::vector<int32_t>* sizes = mutable_parameter_block_sizes();
  for (int j : chain_.chain()) sizes->push_back(BlockSize(j));
  sizes->push_back(3);
  sizes->insert(sizes->end(), chain_.num_scale_blocks(), 1);
  sizes->insert(sizes->end(), chain_.num_shift_blocks(), 3);
}

bool SiteReprojectionResidual::Evaluate(double const* const* parameters, double* residuals,
                                        double** jacobians) const {
  const size_t n = chain_.chain().size();
  BodyPose pose;
  const double* const* scales = parameters + n + 1;
  chain_.Pose(parameters, scales, scales + chain_.num_scale_blocks(), &pose);
  const int b = chain_.bone();
  const Eigen::Map<const Eigen::Vector3d> site(parameters[n]);
  const Eigen::Vector3d x = pose.position[b] + pose.rotation[b] * site;
  Eigen::Vector2d pixel;
  Eigen::Matrix<double, 2, 3> d_pixel;
  if (!camera_->Project(x, &pixel, jacobians != nullptr ? &d_pixel : nullptr)) return false;
  Eigen::Map<Eigen::Vector2d> r(residuals);
  r = sqrt_weight_ * (pixel - detection_);
  if (jacobians == nullptr) return true;
  const Eigen::Matrix<double, 2, 3> m = sqrt_weight_ * d_pixel;
  PointJacobian<2>(*chain_.skeleton(), pose, b, x, m, jacobians);
  if (jacobians[n] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> j(jacobians[n]);
    j = m * pose.rotation[b];
  }
  chain_.OffsetJacobians<2>(pose, m, jacobians + n + 1);
  return true;
}

MountedOrientationResidual::MountedOrientationResidual(ScaledChain chain,
                                                       const Eigen::Matrix3d& mount0,
                                                       const Eigen::Matrix3d& measured_world,
                                                       double weight)
    : chain_(std::move(chain)),
      mount0_(mount0),
      measured_world_(measured_world),
      sqrt_weight_(std::sqrt(weight)) {
  set_num_residuals(3);
  std::vector<int32_t>* sizes = mutable_parameter_block_sizes();
  for (int j : chain_.chain()) sizes->push_back(BlockSize(j));
  sizes->push_back(3);
  sizes->push_back(1);
}

// r0 = Log(A^T S), A = Rz(psi) W, S = G_b M0 Exp(m).
//  - G_b <- Exp(phi) G_b: A^T Exp(phi) S = (A^T S) Exp(S^T phi), dr = J_r^-1(r0) S^T phi.
//  - m: S <- S Exp(J_r(m) dm), dr = J_r^-1(r0) J_r(m) dm.
//  - psi: A <- Exp(dpsi z) A, A^T S <- A^T Exp(-dpsi z) S = (A^T S) Exp(-dpsi S^T z).
bool MountedOrientationResidual::Evaluate(double const* const* parameters, double* residuals,
                                          double** jacobians) const {
  const size_t n = chain_.chain().size();
  BodyPose pose;
  chain_.Pose(parameters, nullptr, nullptr, &pose);
  const int b = chain_.bone();
  const Eigen::Map<const Eigen::Vector3d> m(parameters[n]);
  const double psi = parameters[n + 1][0];
  const Eigen::Matrix3d sensor = pose.rotation[b] * mount0_ * Exp(m);
  const Eigen::Matrix3d measured = Exp(Eigen::Vector3d(0, 0, psi)) * measured_world_;
  const Eigen::Vector3d r0 = Log(measured.transpose() * sensor);
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = sqrt_weight_ * r0;
  if (jacobians == nullptr) return true;
  const Eigen::Matrix3d jr_inv = sqrt_weight_ * InverseRightJacobian(r0);
  RotationJacobian<3>(*chain_.skeleton(), pose, b, Eigen::Matrix3d(jr_inv * sensor.transpose()),
                      jacobians);
  if (jacobians[n] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> j(jacobians[n]);
    j = jr_inv * RightJacobian(m);
  }
  if (jacobians[n + 1] != nullptr) {
    Eigen::Map<Eigen::Vector3d> j(jacobians[n + 1]);
    j = -jr_inv * sensor.transpose() * Eigen::Vector3d::UnitZ();
  }
  return true;
}

}  // namespace mocap
