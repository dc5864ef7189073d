#include "mocap/camera.h"

#include <algorithm>
#include <cmath>

#include "json_util.h"
#include "mocap/so3.h"

namespace mocap {

bool Camera::Project(const Eigen::Vector3d& x, Eigen::Vector2d* pixel,
                     Eigen::Matrix<double, 2, 3>* d_pixel_d_x) const {
  const Eigen::Vector3d xc = rotation * x + translation;
  if (!(xc.z() > kMinDepth)) return false;
  const double iz = 1.0 / xc.z();
  const double u = xc.x() * iz, v = xc.y() * iz;
  const auto& [k1, k2, p1, p2, k3] = distortion;
  const double r2 = u * u + v * v;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const double xd = u * radial + 2.0 * p1 * u * v + p2 * (r2 + 2.0 * u * u);
  const double yd = v * radial + p1 * (r2 + 2.0 * v * v) + 2.0 * p2 * u * v;
  *pixel = Eigen::Vector2d(fx * xd + cx, fy * yd + cy);
  if (d_pixel_d_x != nullptr) {
    const double dradial_dr2 = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
    const double dru = 2.0 * u * dradial_dr2, drv = 2.0 * v * dradial_dr2;
    Eigen::Matrix2d d_dist;  // d(x_d, y_d) / d(u, v)
    d_dist << radial + u * dru + 2.0 * p1 * v + 6.0 * p2 * u, u * drv + 2.0 * p1 * u + 2.0 * p2 * v,
        v * dru + 2.0 * p1 * u + 2.0 * p2 * v, radial + v * drv + 6.0 * p1 * v + 2.0 * p2 * u;
    Eigen::Matrix<double, 2, 3> d_uv;  // d(u, v) / d(X_cam)
    d_uv << iz, 0.0, -u * iz, 0.0, iz, -v * iz;
    const Eigen::Matrix2d f = Eigen::Vector2d(fx, fy).asDiagonal();
    *d_pixel_d_x = f * d_dist * d_uv * rotation;
  }
  return true;
}

Eigen::Vector2d Camera::Undistort(const Eigen::Vector2d& pixel) const {
  const auto& [k1, k2, p1, p2, k3] = distortion;
  const double xd = (pixel.x() - cx) / fx, yd = (pixel.y() - cy) / fy;
  double u = xd, v = yd;
  for (int it = 0; it < 20; ++it) {
    const double r2 = u * u + v * v;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const double dx = 2.0 * p1 * u * v + p2 * (r2 + 2.0 * u * u);
    const double dy = p1 * (r2 + 2.0 * v * v) + 2.0 * p2 * u * v;
    u = (xd - dx) / radial;
    v = (yd - dy) / radial;
  }
  return {u, v};
}

namespace {

// A calibration's distortion is refused when, over the image (radii 0 to its farthest corner,
// normalised), the radial factor leaves [kMinRadial, kMaxRadial] or r * factor stops growing
// (the lens would fold two rays onto one pixel, and Undistort's iteration diverges), or when
// a tangential coefficient exceeds kMaxTangential. Why these: calibrated pinhole lenses, wide
// ones included, keep the factor within 0.7-1.3 at the corner and |p| near 1e-3; a factor off
// by 2 is a fisheye (refused) or a wrong unit, and a k1 of 1e6 moves a pixel by metres.
constexpr double kMinRadial = 0.5, kMaxRadial = 2.0, kMaxTangential = 0.05;
constexpr int kRadiusSamples = 64;

bool DistortionIsPlausible(const Camera& c, std::string* why) {
  const auto& [k1, k2, p1, p2, k3] = c.distortion;
  if (std::abs(p1) > kMaxTangential || std::abs(p2) > kMaxTangential)
    return *why = "a tangential coefficient beyond 0.05", false;
  const double du = std::max(c.cx, c.width - c.cx) / c.fx;
  const double dv = std::max(c.cy, c.height - c.cy) / c.fy;
  const double corner = std::sqrt(du * du + dv * dv);
  double last = 0;
  for (int i = 1; i <= kRadiusSamples; ++i) {
    const double r = corner * i / kRadiusSamples, r2 = r * r;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    if (!(radial >= kMinRadial && radial <= kMaxRadial))
      return *why = "a radial factor of " + std::to_string(radial) + " at normalised radius " +
                    std::to_string(r) + " (allowed 0.5 to 2 over the image)",
             false;
    if (!(r * radial > last)) return *why = "the image folds (r * radial factor decreases)", false;
    last = r * radial;
  }
  return true;
}

}  // namespace

bool Camera::IsValid(std::string* error) const {
  if (!(fx > 0 && fy > 0 && std::isfinite(cx) && std::isfinite(cy))) {
    *error = "camera '" + name + "': focal lengths must be positive and the centre finite";
    return false;
  }
  if (width <= 0 || height <= 0) {
    *error = "camera '" + name + "': image size must be positive";
    return false;
  }
  for (double d : distortion) {
    if (!std::isfinite(d)) {
      *error = "camera '" + name + "': distortion must be finite";
      return false;
    }
  }
  std::string why;
  if (!DistortionIsPlausible(*this, &why)) {
    *error = "camera '" + name + "': implausible distortion (" + why + ")";
    return false;
  }
  if (!rotation.allFinite() || !translation.allFinite() ||
      (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).norm() > 1e-6) {
    *error = "camera '" + name + "': rotation must be a rotation and the translation finite";
    return false;
  }
  return true;
}

static bool ParseRigJsonUnguarded(const std::string& text, Rig* out, std::string* error) {
  nlohmann::json j;
  if (!internal::ParseJson(text, &j, error)) return false;
  if (!j.is_object() || j.value("format", "") != "mocap.rig/1" || !j.contains("cameras") ||
      !j["cameras"].is_array()) {
    *error = "not a mocap.rig/1 file";
    return false;
  }
  Rig rig;
  for (const auto& jc : j["cameras"]) {
    Camera c;
    Eigen::Vector3d rotvec;
    if (!jc.is_object()) {
      *error = "camera entry is not an object";
      return false;
    }
    c.name = jc.value("name", "cam" + std::to_string(rig.cameras.size()));
    const bool ok = jc.contains("width") && jc.contains("height") &&
                    jc["width"].is_number_integer() && jc["height"].is_number_integer() &&
                    jc.contains("fx") && jc.contains("fy") && jc.contains("cx") &&
                    jc.contains("cy") && jc["fx"].is_number() && jc["fy"].is_number() &&
                    jc["cx"].is_number() && jc["cy"].is_number() && jc.contains("rotation") &&
                    internal::ReadVector3(jc["rotation"], &rotvec) && jc.contains("translation") &&
                    internal::ReadVector3(jc["translation"], &c.translation) &&
                    (!jc.contains("distortion") ||
                     internal::ReadVector(jc["distortion"], 5, c.distortion.data()));
    if (!ok) {
      *error = "camera '" + c.name + "': missing or malformed field";
      return false;
    }
    c.width = jc["width"].get<int>();
    c.height = jc["height"].get<int>();
    c.fx = jc["fx"].get<double>();
    c.fy = jc["fy"].get<double>();
    c.cx = jc["cx"].get<double>();
    c.cy = jc["cy"].get<double>();
    c.rotation = Exp(rotvec);
    if (!c.IsValid(error)) return false;
    rig.cameras.push_back(c);
  }
  *out = std::move(rig);
  return true;
}

bool ParseRigJson(const std::string& text, Rig* out, std::string* error) {
  return internal::Guarded(error, [&] { return ParseRigJsonUnguarded(text, out, error); });
}

bool LoadRigJson(const std::string& path, Rig* out, std::string* error) {
  return internal::LoadFile(
      path, error, [&](const std::string& text) { return ParseRigJson(text, out, error); });
}

std::string RigToJson(const Rig& rig) {
  nlohmann::json j;
  j["format"] = "mocap.rig/1";
  j["cameras"] = nlohmann::json::array();
  for (const Camera& c : rig.cameras) {
    const Eigen::Vector3d r = Log(c.rotation);
    j["cameras"].push_back(
        {{"name", c.name},
         {"width", c.width},
         {"height", c.height},
         {"fx", c.fx},
         {"fy", c.fy},
         {"cx", c.cx},
         {"cy", c.cy},
         {"distortion", c.distortion},
         {"rotation", {r.x(), r.y(), r.z()}},
         {"translation", {c.translation.x(), c.translation.y(), c.translation.z()}}});
  }
  return j.dump(2);
}

}  // namespace mocap
