#include "mocap/so3.h"

#include <cmath>

namespace mocap {
namespace {
// Below this angle the closed forms lose precision; Taylor series take over.
constexpr double kSmallAngle = 1e-6;
}  // namespace

Eigen::Matrix3d Exp(const Eigen::Vector3d& w) {
  const double theta2 = w.squaredNorm();
  const Eigen::Matrix3d k = Skew(w);
  if (theta2 < kSmallAngle * kSmallAngle) {
    return Eigen::Matrix3d::Identity() + k + 0.5 * k * k;
  }
  const double theta = std::sqrt(theta2);
  return Eigen::Matrix3d::Identity() + (std::sin(theta) / theta) * k +
         ((1.0 - std::cos(theta)) / theta2) * k * k;
}

Eigen::Vector3d Log(const Eigen::Matrix3d& r) {
  // Through the quaternion: robust near 0 and near pi.
  Eigen::Quaterniond q(r);
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  const double n = q.vec().norm();
  if (n < kSmallAngle) return (2.0 / q.w()) * q.vec();
  const double theta = 2.0 * std::atan2(n, q.w());
  return (theta / n) * q.vec();
}

Eigen::Matrix3d RightJacobian(const Eigen::Vector3d& w) {
  const double theta2 = w.squaredNorm();
  const Eigen::Matrix3d k = Skew(w);
  if (theta2 < kSmallAngle * kSmallAngle) {
    return Eigen::Matrix3d::Identity() - 0.5 * k + (1.0 / 6.0) * k * k;
  }
  const double theta = std::sqrt(theta2);
  return Eigen::Matrix3d::Identity() - ((1.0 - std::cos(theta)) / theta2) * k +
         ((theta - std::sin(theta)) / (theta2 * theta)) * k * k;
}

Eigen::Matrix3d InverseRightJacobian(const Eigen::Vector3d& w) {
  const double theta2 = w.squaredNorm();
  const Eigen::Matrix3d k = Skew(w);
  if (theta2 < kSmallAngle * kSmallAngle) {
    return Eigen::Matrix3d::Identity() + 0.5 * k + (1.0 / 12.0) * k * k;
  }
  const double theta = std::sqrt(theta2);
  const double c = 1.0 / theta2 - (1.0 + std::cos(theta)) / (2.0 * theta * std::sin(theta));
  return Eigen::Matrix3d::Identity() + 0.5 * k + c * k * k;
}

double AngleBetween(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Log(a.transpose() * b).norm();
}

}  // namespace mocap
