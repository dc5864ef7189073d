/* Transcendental functions of the orientation filter as polynomials of our own, so that
 * the MCU and the host compute the same bits (see imu_filter_math.h). */
#include "imu_filter_math.h"

float imu_filter_atan2(float y, float x) {
  const float ax = fabsf(x);
  const float ay = fabsf(y);
  const float big = ax > ay ? ax : ay;
  const float small = ax > ay ? ay : ax;
  if (!(big > 0.0f)) {
    return 0.0f;
  }
  /* atan(t) for t in [0, 1]: odd polynomial of degree 15, weighted least-squares fit
   * (Lawson iterations) to the maximum error, 1.1e-7 rad in float32. */
  const float t = small / big;
  const float t2 = t * t;
  float p = -0.00405449f;
  p = p * t2 + 0.02186269f;
  p = p * t2 - 0.05591196f;
  p = p * t2 + 0.09642172f;
  p = p * t2 - 0.1390862f;
  p = p * t2 + 0.19946563f;
  p = p * t2 - 0.3332986f;
  p = p * t2 + 0.99999934f;
  float angle = p * t;
  if (ay > ax) {
    angle = 0.5f * IMU_FILTER_PI - angle;
  }
  if (x < 0.0f) {
    angle = IMU_FILTER_PI - angle;
  }
  return y < 0.0f ? -angle : angle;
}

void imu_filter_sincos(float angle_rad, float *const sin_out, float *const cos_out) {
  /* Taylor series to degree 13 / 14: below float32 resolution on [-pi/2, pi/2]. */
  const float x2 = angle_rad * angle_rad;
  float s = 1.0f / 6227020800.0f;
  s = s * x2 - 1.0f / 39916800.0f;
  s = s * x2 + 1.0f / 362880.0f;
  s = s * x2 - 1.0f / 5040.0f;
  s = s * x2 + 1.0f / 120.0f;
  s = s * x2 - 1.0f / 6.0f;
  s = s * x2 + 1.0f;
  float c = -1.0f / 87178291200.0f;
  c = c * x2 + 1.0f / 479001600.0f;
  c = c * x2 - 1.0f / 3628800.0f;
  c = c * x2 + 1.0f / 40320.0f;
  c = c * x2 - 1.0f / 720.0f;
  c = c * x2 + 1.0f / 24.0f;
  c = c * x2 - 0.5f;
  c = c * x2 + 1.0f;
  *sin_out = s * angle_rad;
  *cos_out = c;
}

/* 1 - exp(-x) for x in [0, 0.5]: series, no cancellation. */
static float imu_filter_one_minus_exp_small(float x) {
  float term = x;
  float sum = x;
  for (int k = 2; k <= 9; ++k) {
    term *= -x / (float)k;
    sum += term;
  }
  return sum;
}

float imu_filter_gain(float period_s, float time_constant_s) {
  if (!(time_constant_s > 0.0f)) {
    return 1.0f;
  }
  float x = period_s / time_constant_s;
  if (x <= 0.5f) {
    return imu_filter_one_minus_exp_small(x);
  }
  /* exp(-x) = exp(-x / 2^k)^(2^k) */
  int halvings = 0;
  while (x > 0.5f && halvings < 40) {
    x *= 0.5f;
    ++halvings;
  }
  float e = 1.0f - imu_filter_one_minus_exp_small(x);
  for (int k = 0; k < halvings; ++k) {
    e *= e;
  }
  return 1.0f - e;
}
