/* The orientation filter's parts (imu_filter.c, imu_filter_bias.c, imu_filter_mag.c) as
 * seen by each other; not part of the filter's interface. */
#ifndef FIRMWARE_CORE_IMU_FILTER_INTERNAL_H
#define FIRMWARE_CORE_IMU_FILTER_INTERNAL_H

#include <stddef.h>

#include "imu_filter.h"
#include "imu_filter_math.h"

/* Starts a low-pass of mean delay `time_constant_s` and damping ratio `damping`, run every
 * `period_s` (imu_filter_lowpass_t). Shorter than 4 periods: it passes the input through. */
static inline void imu_filter_lowpass_init(imu_filter_lowpass_t *const lp, float period_s,
                                           float time_constant_s, float damping) {
  const bool pass = !(time_constant_s >= 4.0f * period_s);
  lp->damping2 = 2.0f * damping;
  lp->gain = pass ? 0.0f : lp->damping2 * period_s / time_constant_s;
  lp->average_steps = pass ? 0u : (uint32_t)(time_constant_s / period_s + 0.5f);
  lp->steps = pass ? 0u : 1u;
}

/* One step over n values: output y, scaled rate u. While starting, y is the running mean
 * of the inputs (u = 0), until it spans one time constant. */
static inline void imu_filter_lowpass_step(imu_filter_lowpass_t *const lp, const float *const x,
                                           float *const y, float *const u, size_t n) {
  if (lp->steps == 0u) {
    const float g = lp->gain;
    const float d = lp->damping2;
    if (g == 0.0f) {
      for (size_t i = 0; i < n; ++i) {
        y[i] = x[i];
      }
      return;
    }
    for (size_t i = 0; i < n; ++i) {
      u[i] += g * ((x[i] - y[i]) - d * u[i]);
      y[i] += g * u[i];
    }
    return;
  }
  const float g = 1.0f / (float)lp->steps;
  for (size_t i = 0; i < n; ++i) {
    y[i] += g * (x[i] - y[i]);
  }
  if (++lp->steps > lp->average_steps) {
    lp->steps = 0u;
  }
}

/* q(S->E6) = inclination ⊗ strapdown. */
static inline void imu_filter_quat_6d(const imu_filter_t *const filter, float q[4]) {
  imu_filter_quat_multiply(filter->acc_quat, filter->gyr_quat, q);
}

static inline void imu_filter_count(uint32_t *const counter) {
  if (*counter < UINT32_MAX) {
    ++*counter;
  }
}

/* imu_filter_bias.c */
void imu_filter_bias_init(imu_filter_t *const filter);
void imu_filter_rest_gyr(imu_filter_t *const filter, const float gyr_rads[3]);
void imu_filter_rest_acc(imu_filter_t *const filter, const float acc_mps2[3]);
/* After the inclination correction: one bias estimator step every bias_decimation samples. */
void imu_filter_bias_step(imu_filter_t *const filter);

/* imu_filter_mag.c */
void imu_filter_mag_init(imu_filter_t *const filter);
void imu_filter_mag_update(imu_filter_t *const filter, const float mag_ut[3]);

#endif /* FIRMWARE_CORE_IMU_FILTER_INTERNAL_H */
