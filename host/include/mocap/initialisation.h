// First-frame initialisation: a starting pose from one frame's observations, without
// ground truth.
//  - Root orientation: from an IMU on the root bone; else a rigid (Kabsch) fit of the
//    rest-pose torso sites (hips, shoulders: sites on or hanging from the bones named
//    pelvis/root, spine*, clavicle*) to their triangulated keypoints; else facing the camera.
//  - Root position: from keypoints triangulated in two or more views; else, with one
//    view, along the ray of the keypoints' centroid at the depth their spread implies;
//    else unknown (the origin).
//  - Bone orientations: from the IMUs on them (R_ig R_i R_m^T), top-down; others at rest.
#ifndef MOCAP_INITIALISATION_H_
#define MOCAP_INITIALISATION_H_

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "mocap/camera.h"
#include "mocap/sites.h"
#include "mocap/skeleton.h"

namespace mocap {

struct Detection {
  int camera = 0;
  int keypoint = 0;
  Eigen::Vector2d pixel{0, 0};
  double confidence = 0;
};

// Linear (DLT) triangulation from undistorted rays, weighted by confidence.
// False when fewer than two views or the point is not in front of every camera.
bool TriangulatePoint(const Rig& rig, const std::vector<Detection>& views, Eigen::Vector3d* x);

struct InitialPose {
  Eigen::VectorXd theta;
  bool position_known = false;
};

// imu_world[i]: the measured world orientation of IMU i's sensor (R_ig R_i), if any.
InitialPose EstimateInitialPose(const Skeleton& skeleton, const Rig& rig,
                                const KeypointLayout& layout, const std::vector<ImuSite>& imus,
                                const std::vector<Detection>& detections,
                                const std::vector<std::optional<Eigen::Matrix3d>>& imu_world);

}  // namespace mocap

#endif  // MOCAP_INITIALISATION_H_
