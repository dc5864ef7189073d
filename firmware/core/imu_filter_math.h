/* Float32 vector and quaternion arithmetic of the orientation filter (imu_filter.h).
 *
 * Everything here uses only + - * / and sqrtf, which IEEE 754 rounds the same way on
 * every target (with -ffp-contract=off): the filter gives bit-identical results on the
 * Cortex-M4F and on the host. The few transcendental functions the filter needs are
 * polynomials of our own (imu_filter_math.c) rather than libm's, whose last bits differ
 * between newlib and glibc. Quaternions are w, x, y, z (Hamilton convention).
 */
#ifndef FIRMWARE_CORE_IMU_FILTER_MATH_H
#define FIRMWARE_CORE_IMU_FILTER_MATH_H

#include <math.h>
#include <stdbool.h>

#define IMU_FILTER_PI 3.14159265358979f

static inline float imu_filter_dot3(const float a[3], const float b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* True when every component is finite and |component| <= limit (NaN fails too). */
static inline bool imu_filter_vector_ok(const float v[3], float limit) {
  return fabsf(v[0]) <= limit && fabsf(v[1]) <= limit && fabsf(v[2]) <= limit;
}

/* out = a ⊗ b; out may alias neither a nor b. */
static inline void imu_filter_quat_multiply(const float a[4], const float b[4], float out[4]) {
  out[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
  out[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
  out[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
  out[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
}

/* out = q v q* (v expressed in the frame q rotates into); out may not alias v. */
static inline void imu_filter_quat_rotate(const float q[4], const float v[3], float out[3]) {
  /* t = 2 (q_vec × v); out = v + w t + q_vec × t */
  const float tx = 2.0f * (q[2] * v[2] - q[3] * v[1]);
  const float ty = 2.0f * (q[3] * v[0] - q[1] * v[2]);
  const float tz = 2.0f * (q[1] * v[1] - q[2] * v[0]);
  out[0] = v[0] + q[0] * tx + (q[2] * tz - q[3] * ty);
  out[1] = v[1] + q[0] * ty + (q[3] * tx - q[1] * tz);
  out[2] = v[2] + q[0] * tz + (q[1] * ty - q[2] * tx);
}

/* Renormalises a quaternion that is already within ~1e-3 of unit length: one Newton
 * step of 1/sqrt, no sqrt or division. */
static inline void imu_filter_quat_renormalise(float q[4]) {
  const float n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  const float s = 1.5f - 0.5f * n2;
  q[0] *= s;
  q[1] *= s;
  q[2] *= s;
  q[3] *= s;
}

/* Angle in (-pi, pi]. */
static inline float imu_filter_wrap_angle(float angle_rad) {
  if (angle_rad > IMU_FILTER_PI) {
    return angle_rad - 2.0f * IMU_FILTER_PI;
  }
  if (angle_rad <= -IMU_FILTER_PI) {
    return angle_rad + 2.0f * IMU_FILTER_PI;
  }
  return angle_rad;
}

/* atan2(y, x) in rad, |error| < 2e-7 rad; 0 for (0, 0). */
float imu_filter_atan2(float y, float x);

/* sin and cos of an angle in [-pi/2, pi/2], |error| < 1e-7. */
void imu_filter_sincos(float angle_rad, float *const sin_out, float *const cos_out);

/* Gain 1 - exp(-period/time_constant) of a first-order low-pass whose time constant is
 * `time_constant_s` (0 or less: 1, no filtering). */
float imu_filter_gain(float period_s, float time_constant_s);

#endif /* FIRMWARE_CORE_IMU_FILTER_MATH_H */
