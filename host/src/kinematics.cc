#include "mocap/kinematics.h"

#include <cstdint>
#include <cstring>

#include "mocap/so3.h"

namespace mocap {
namespace {

// G_b, p_b, A_b of bone b from its block and its (up to date) parent.
void ComputeBone(const Skeleton& skeleton, int b, const double* block, BodyPose* out) {
  const double* rotation = b == 0 ? block + 3 : block;
  const Eigen::Map<const Eigen::Vector3d> w(rotation);
  const Eigen::Matrix3d local = Exp(w);
  const int parent = skeleton.bone(b).parent;
  if (parent < 0) {
    out->rotation[b] = local;
    out->position[b] = Eigen::Map<const Eigen::Vector3d>(block) + skeleton.bone(b).offset;
  } else {
    out->rotation[b] = out->rotation[parent] * local;
    out->position[b] = out->position[parent] + out->rotation[parent] * skeleton.bone(b).offset;
  }
  out->axes[b] = out->rotation[b] * RightJacobian(w);
}

// Bitwise equality of n doubles, as memcmp (so a NaN parameter equals itself) but inline:
// every residual checks its chain's blocks at every evaluation.
bool SameBits(const double* a, const double* b, int n) {
  for (int k = 0; k < n; ++k) {
    uint64_t x, y;
    std::memcpy(&x, a + k, sizeof x);
    std::memcpy(&y, b + k, sizeof y);
    if (x != y) return false;
  }
  return true;
}

void Resize(int n, BodyPose* pose) {
  pose->rotation.resize(n);
  pose->position.resize(n);
  pose->axes.resize(n);
}

}  // namespace

void ForwardKinematics(const Skeleton& skeleton, const double* theta, BodyPose* out) {
  Resize(skeleton.num_bones(), out);
  for (int b = 0; b < skeleton.num_bones(); ++b)
    ComputeBone(skeleton, b, theta + BlockOffset(b), out);
}

std::vector<double*> ChainBlocks(const Skeleton& skeleton, int b, double* theta) {
  std::vector<double*> blocks;
  for (int j : skeleton.Chain(b)) blocks.push_back(theta + BlockOffset(j));
  return blocks;
}

std::vector<int> ChainBlockSizes(const Skeleton& skeleton, int b) {
  std::vector<int> sizes;
  sizes.reserve(skeleton.Chain(b).size());
  for (int j : skeleton.Chain(b)) sizes.push_back(BlockSize(j));
  return sizes;
}

KinematicsCache::KinematicsCache(const Skeleton* skeleton)
    : skeleton_(skeleton),
      key_(skeleton->num_bones()),
      version_(skeleton->num_bones(), 0),
      parent_version_(skeleton->num_bones(), 0) {
  Resize(skeleton->num_bones(), &pose_);
}

const BodyPose& KinematicsCache::Update(int b, double const* const* chain_blocks) {
  const std::vector<int>& chain = skeleton_->Chain(b);
  for (int i = static_cast<int>(chain.size()) - 1; i >= 0; --i) {  // root first
    const int j = chain[i];
    const int parent = skeleton_->bone(j).parent;
    const uint64_t parent_version = parent < 0 ? 0 : version_[parent];
    if (version_[j] != 0 && parent_version_[j] == parent_version &&
        SameBits(key_[j].data(), chain_blocks[i], BlockSize(j))) {
      continue;
    }
    std::memcpy(key_[j].data(), chain_blocks[i], sizeof(double) * BlockSize(j));
    ComputeBone(*skeleton_, j, chain_blocks[i], &pose_);
    parent_version_[j] = parent_version;
    version_[j] = next_version_++;
  }
  return pose_;
}

}  // namespace mocap
