// Sites: points and sensors attached to bones.
//
// A keypoint site is where a 2D detector's keypoint sits on the body: a bone plus an
// offset in that bone's frame (metres). A detector's "hip" is not the hip joint, so
// offsets are per layout and are scaled to the subject (see KeypointLayout::ScaledTo).
//
// An IMU site is a sensor strapped to a bone:
//   mount      R_m: sensor frame -> bone frame
//   offset     sensor origin in the bone frame, metres
//   reference  R_ig: the sensor's own reference frame ("local earth") -> world
// so the sensor's orientation in world is G_b * R_m, and a measured orientation R_i
// (sensor -> reference) maps to world as R_ig * R_i.
#ifndef MOCAP_SITES_H_
#define MOCAP_SITES_H_

#include <Eigen/Core>
#include <string>
#include <vector>

#include "mocap/skeleton.h"

namespace mocap {

struct Site {
  int bone = 0;
  Eigen::Vector3d offset{0, 0, 0};  // bone frame, metres
};

struct KeypointLayout {
  std::string name;                // "coco17", "body25b", "blazepose33", ...
  double reference_height = 0.0;   // RestHeight() of the skeleton the offsets were made for
  std::vector<std::string> names;  // keypoint names in detector order
  std::vector<Site> sites;         // same order

  int size() const { return static_cast<int>(sites.size()); }
  // Offsets scaled by skeleton.RestHeight() / reference_height.
  KeypointLayout ScaledTo(const Skeleton& skeleton) const;
};

struct ImuSite {
  std::string name;
  int bone = 0;
  Eigen::Matrix3d mount = Eigen::Matrix3d::Identity();      // sensor -> bone
  Eigen::Vector3d offset{0, 0, 0};                          // bone frame, metres
  Eigen::Matrix3d reference = Eigen::Matrix3d::Identity();  // IMU reference -> world
};

// Layout file: {"format": "mocap.layout/1", "name": ..., "reference_height": m,
//   "keypoints": [{"name": ..., "bone": ..., "offset": [x, y, z]}, ...]}
bool LoadKeypointLayoutJson(const std::string& path, const Skeleton& skeleton, KeypointLayout* out,
                            std::string* error);
bool ParseKeypointLayoutJson(const std::string& text, const Skeleton& skeleton, KeypointLayout* out,
                             std::string* error);
// The layout with its offsets as they are for `skeleton` (reference_height = its rest
// height: loading it for that skeleton and scaling to it changes nothing).
std::string KeypointLayoutToJson(const Skeleton& skeleton, const KeypointLayout& layout);

// IMU set file: {"format": "mocap.imus/1", "imus": [{"name": ..., "bone": ...,
//   "mount": [rotation vector], "offset": [x, y, z], "reference": [rotation vector]}]}
// "mount", "offset" and "reference" default to identity / zero.
bool LoadImuSitesJson(const std::string& path, const Skeleton& skeleton, std::vector<ImuSite>* out,
                      std::string* error);
bool ParseImuSitesJson(const std::string& text, const Skeleton& skeleton, std::vector<ImuSite>* out,
                       std::string* error);
std::string ImuSitesToJson(const Skeleton& skeleton, const std::vector<ImuSite>& imus);

}  // namespace mocap

#endif  // MOCAP_SITES_H_
