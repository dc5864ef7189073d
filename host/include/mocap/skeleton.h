// The kinematic skeleton: a tree of bones, each with a fixed offset from its parent.
//
// Pose vector theta (the paper's 66-D for the default 21-bone skeleton):
//   theta[0:3]           root translation, metres, world frame
//   theta[3:6]           root rotation, rotation vector (bone -> world)
//   theta[6+3(b-1) : +3] rotation of bone b relative to its parent, for b = 1..n-1
// Every bone frame coincides with the world axes in the rest pose (all rotations zero).
// World frame: right-handed, z up, metres. Default rest pose: T-pose facing +x, left +y.
//
// Forward kinematics (slide "Overview"): T_b = T_parent(b) * [R(theta_b) | t_b], i.e.
//   G_b = G_parent * Exp(theta_b),   p_b = p_parent + G_parent * t_b.
#ifndef MOCAP_SKELETON_H_
#define MOCAP_SKELETON_H_

#include <Eigen/Core>
#include <string>
#include <vector>

namespace mocap {

// The bones of the paper's skeleton, in the order of the default skeleton file.
extern const char* const kCanonicalBoneNames[21];

class Skeleton {
 public:
  struct Bone {
    std::string name;
    int parent = -1;                  // index of the parent bone, -1 for the root
    Eigen::Vector3d offset{0, 0, 0};  // t_b: bone origin in the parent frame, metres
  };

  Skeleton() = default;
  // Bones must be ordered parents-first with exactly one root at index 0.
  static bool Create(std::vector<Bone> bones, Skeleton* out, std::string* error);

  int num_bones() const { return static_cast<int>(bones_.size()); }
  int pose_dim() const { return 3 + 3 * num_bones(); }
  const Bone& bone(int b) const { return bones_[b]; }
  const std::vector<Bone>& bones() const { return bones_; }
  // -1 when absent.
  int BoneIndex(const std::string& name) const;
  // Bone b and its ancestors, b first, root last.
  const std::vector<int>& Chain(int b) const { return chains_[b]; }
  // Offset of bone b's rotation parameters in theta (3 for the root).
  static int RotationIndex(int b) { return 3 + 3 * b; }
  // Rest-pose height from the lowest bone origin to the highest, metres.
  double RestHeight() const;

 private:
  std::vector<Bone> bones_;
  std::vector<std::vector<int>> chains_;
};

// Skeleton file (documented in host/README.md): JSON
//   {"format": "mocap.skeleton/1", "units": "m",
//    "bones": [{"name": "pelvis", "parent": null, "offset": [x, y, z]}, ...]}
bool LoadSkeletonJson(const std::string& path, Skeleton* out, std::string* error);
bool ParseSkeletonJson(const std::string& text, Skeleton* out, std::string* error);
std::string SkeletonToJson(const Skeleton& skeleton);

}  // namespace mocap

#endif  // MOCAP_SKELETON_H_
