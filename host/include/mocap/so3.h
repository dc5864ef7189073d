// SO(3) helpers on rotation vectors (axis-angle, radians).
//
// Conventions used everywhere in the host library:
//  - A rotation vector w encodes R = Exp(w) = exp([w]_x); |w| is the angle in radians.
//  - Perturbations are on the right in the parameter space:
//      Exp(w + d) ~= Exp(w) * Exp(RightJacobian(w) * d)
//      Log(Exp(w) * Exp(d)) ~= w + InverseRightJacobian(w) * d
//  - Eigen quaternions are constructed (w, x, y, z) but stored (x, y, z, w).
#ifndef MOCAP_SO3_H_
#define MOCAP_SO3_H_

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace mocap {

// [v]_x: the matrix with [v]_x * u = v.cross(u).
inline Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

Eigen::Matrix3d Exp(const Eigen::Vector3d& w);
Eigen::Vector3d Log(const Eigen::Matrix3d& r);
Eigen::Matrix3d RightJacobian(const Eigen::Vector3d& w);
Eigen::Matrix3d InverseRightJacobian(const Eigen::Vector3d& w);

// Geodesic angle between two rotations, radians in [0, pi].
double AngleBetween(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b);

}  // namespace mocap

#endif  // MOCAP_SO3_H_
