// Calibrated cameras: pinhole with OpenCV distortion (k1, k2, p1, p2, k3).
//
// Frames: world as in skeleton.h; camera frame as OpenCV (x right, y down, z forward).
// X_cam = rotation * X_world + translation   (world -> camera)
// (u, v) = (X/Z, Y/Z); r2 = u^2 + v^2; radial = 1 + k1 r2 + k2 r2^2 + k3 r2^3
// x_d = u radial + 2 p1 u v + p2 (r2 + 2 u^2);   y_d = v radial + p1 (r2 + 2 v^2) + 2 p2 u v
// pixel = (fx x_d + cx, fy y_d + cy), origin at the centre of the top-left pixel.
#ifndef MOCAP_CAMERA_H_
#define MOCAP_CAMERA_H_

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

namespace mocap {

struct Camera {
  // Points closer to the camera plane than this (metres) are not projected.
  static constexpr double kMinDepth = 0.05;

  std::string name;
  int width = 0, height = 0;                               // pixels
  double fx = 0, fy = 0, cx = 0, cy = 0;                   // pixels
  std::array<double, 5> distortion{};                      // k1, k2, p1, p2, k3
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // world -> camera
  Eigen::Vector3d translation{0, 0, 0};                    // world -> camera, metres

  // False (outputs untouched) when x is behind or too close to the camera plane.
  // d_pixel_d_x may be null.
  bool Project(const Eigen::Vector3d& x, Eigen::Vector2d* pixel,
               Eigen::Matrix<double, 2, 3>* d_pixel_d_x = nullptr) const;
  // Normalised image coordinates (u, v) of a pixel, by fixed-point iteration.
  Eigen::Vector2d Undistort(const Eigen::Vector2d& pixel) const;
  // Camera centre in world coordinates.
  Eigen::Vector3d Center() const { return -rotation.transpose() * translation; }
  bool IsValid(std::string* error) const;
};

struct Rig {
  std::vector<Camera> cameras;
};

// Rig file: {"format": "mocap.rig/1", "cameras": [{"name": ..., "width": px, "height": px,
//   "fx": px, "fy": px, "cx": px, "cy": px, "distortion": [k1, k2, p1, p2, k3],
//   "rotation": [rotation vector, world -> camera], "translation": [m, world -> camera]}]}
bool LoadRigJson(const std::string& path, Rig* out, std::string* error);
bool ParseRigJson(const std::string& text, Rig* out, std::string* error);
std::string RigToJson(const Rig& rig);

}  // namespace mocap

#endif  // MOCAP_CAMERA_H_
