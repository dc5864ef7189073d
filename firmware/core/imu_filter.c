/* The orientation filter (imu_filter.h): coefficients, strapdown integration, inclination
 * correction, and the outputs. Bias estimation: imu_filter_bias.c; heading: imu_filter_mag.c. */
#include "imu_filter.h"

#include <string.h>

#include "imu_filter_internal.h"
#include "imu_filter_math.h"

#define IMU_FILTER_DEG (IMU_FILTER_PI / 180.0f)
/* Plausibility limits of the inputs; beyond them a vector is bad data (skipped, counted). */
#define IMU_FILTER_GYR_LIMIT_RADS 100.0f  /* 5,700 deg/s, beyond any gyroscope's range */
#define IMU_FILTER_ACC_LIMIT_MPS2 2000.0f /* 200 g */
#define IMU_FILTER_MAG_LIMIT_UT 10000.0f  /* 1 mT */
#define IMU_FILTER_TIME_LIMIT_S 1.0e6f    /* saturation of the time counters */

const imu_filter_settings_t imu_filter_settings_default = {
    .acc_time_constant_s = 2.5f,
    .acc_damping = 0.707f,
    .mag_time_constant_s = 15.0f,
    .rest_time_s = 1.5f,
    .rest_filter_time_constant_s = 0.5f,
    .rest_gyr_threshold_rads = 2.0f * IMU_FILTER_DEG,
    .rest_acc_threshold_mps2 = 0.5f,
    .bias_limit_rads = 2.0f * IMU_FILTER_DEG,
    .bias_sigma_init_rads = 0.5f * IMU_FILTER_DEG,
    .bias_sigma_motion_rads = 0.1f * IMU_FILTER_DEG,
    .bias_sigma_rest_rads = 0.03f * IMU_FILTER_DEG,
    .bias_forgetting_time_s = 100.0f,
    .bias_vertical_forgetting = 1.0e-4f,
    .bias_update_rate_hz = 50.0f,
    .mag_current_time_constant_s = 0.05f,
    .mag_ref_time_constant_s = 20.0f,
    .mag_norm_threshold = 0.15f,
    .mag_dip_threshold_rad = 14.0f * IMU_FILTER_DEG,
    .mag_new_time_s = 20.0f,
    .mag_new_first_time_s = 5.0f,
    .mag_new_min_gyr_rads = 20.0f * IMU_FILTER_DEG,
    .mag_min_undisturbed_time_s = 1.0f,
    .mag_max_rejection_time_s = 60.0f,
    .mag_rejection_factor = 2.0f,
    .motion_bias_enabled = true,
    .rest_bias_enabled = true,
    .mag_rejection_enabled = true,
};

static bool imu_filter_in_range(float value, float low, float high) {
  return value >= low && value <= high; /* false for NaN */
}

bool imu_filter_settings_valid(const imu_filter_settings_t *const s, float sample_period_s) {
  if (s == NULL || !imu_filter_in_range(sample_period_s, 1.0e-5f, 0.1f)) {
    return false;
  }
  const float times[] = {
      s->acc_time_constant_s,         s->mag_time_constant_s,     s->rest_time_s,
      s->rest_filter_time_constant_s, s->bias_forgetting_time_s,  s->mag_current_time_constant_s,
      s->mag_ref_time_constant_s,     s->mag_new_time_s,          s->mag_new_first_time_s,
      s->mag_min_undisturbed_time_s,  s->mag_max_rejection_time_s};
  for (size_t i = 0; i < sizeof times / sizeof times[0]; ++i) {
    if (!imu_filter_in_range(times[i], 0.0f, 1.0e5f)) {
      return false;
    }
  }
  return imu_filter_in_range(s->acc_damping, 0.5f, 2.0f) &&
         imu_filter_in_range(s->rest_gyr_threshold_rads, 0.0f, 10.0f) &&
         imu_filter_in_range(s->rest_acc_threshold_mps2, 0.0f, 100.0f) &&
         imu_filter_in_range(s->bias_limit_rads, 0.0f, 1.0f) &&
         imu_filter_in_range(s->bias_sigma_init_rads, 1.0e-6f, 1.0f) &&
         imu_filter_in_range(s->bias_sigma_motion_rads, 1.0e-6f, 1.0f) &&
         imu_filter_in_range(s->bias_sigma_rest_rads, 1.0e-6f, 1.0f) &&
         imu_filter_in_range(s->bias_vertical_forgetting, 1.0e-10f, 1.0f) &&
         imu_filter_in_range(s->bias_update_rate_hz, 1.0e-3f, 1.0e5f) &&
         imu_filter_in_range(s->mag_norm_threshold, 0.0f, 10.0f) &&
         imu_filter_in_range(s->mag_dip_threshold_rad, 0.0f, IMU_FILTER_PI) &&
         imu_filter_in_range(s->mag_new_min_gyr_rads, 0.0f, 100.0f) &&
         imu_filter_in_range(s->mag_rejection_factor, 1.0f, 1.0e3f);
}

static void imu_filter_coefficients(imu_filter_t *const filter, float sample_period_s) {
  const imu_filter_settings_t *const s = &filter->settings;
  imu_filter_coefficients_t *const c = &filter->coeff;
  c->sample_period_s = sample_period_s;
  c->rest_gyr_threshold2 = s->rest_gyr_threshold_rads * s->rest_gyr_threshold_rads;
  c->rest_acc_threshold2 = s->rest_acc_threshold_mps2 * s->rest_acc_threshold_mps2;
  c->mag_gain = imu_filter_gain(sample_period_s, s->mag_time_constant_s);
  c->mag_ref_gain = imu_filter_gain(sample_period_s, s->mag_ref_time_constant_s);
  c->mag_current_gain = imu_filter_gain(sample_period_s, 0.5f * s->mag_current_time_constant_s);
  const float decimation = 1.0f / (s->bias_update_rate_hz * sample_period_s) + 0.5f;
  c->bias_decimation = decimation < 1.0f ? 1u : decimation > 1000.0f ? 1000u : (uint32_t)decimation;
  c->bias_period_s = (float)c->bias_decimation * sample_period_s;
}

void imu_filter_init(imu_filter_t *const filter, const imu_filter_settings_t *const settings,
                     float sample_period_s) {
  memset(filter, 0, sizeof *filter);
  filter->gyr_quat[0] = 1.0f;
  filter->acc_quat[0] = 1.0f;
  filter->coeff.valid = imu_filter_settings_valid(settings, sample_period_s);
  if (!filter->coeff.valid) {
    return;
  }
  filter->settings = *settings;
  imu_filter_coefficients(filter, sample_period_s);
  imu_filter_lowpass_init(&filter->acc_filter, sample_period_s, settings->acc_time_constant_s,
                          settings->acc_damping);
  imu_filter_bias_init(filter);
  imu_filter_mag_init(filter);
}

/* q(S->I) ⊗= exp(½ (gyr - bias) T): the half angle's cosine and sine as series in its
 * square, no trigonometry and no square root. */
static void imu_filter_integrate(imu_filter_t *const filter, const float gyr_rads[3]) {
  const float half_period = 0.5f * filter->coeff.sample_period_s;
  const float *const bias = filter->bias.bias_rads;
  const float w[3] = {gyr_rads[0] - bias[0], gyr_rads[1] - bias[1], gyr_rads[2] - bias[2]};
  const float phi2 = imu_filter_dot3(w, w) * half_period * half_period;
  const float c = 1.0f + phi2 * (-0.5f + phi2 * (1.0f / 24.0f - phi2 * (1.0f / 720.0f)));
  const float s = half_period *
                  (1.0f + phi2 * (-1.0f / 6.0f + phi2 * (1.0f / 120.0f - phi2 * (1.0f / 5040.0f))));
  const float step[4] = {c, s * w[0], s * w[1], s * w[2]};
  float q[4];
  imu_filter_quat_multiply(filter->gyr_quat, step, q);
  const float n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  if (!(n2 > 0.25f)) {
    return; /* a step far beyond the series' range: keep the last orientation */
  }
  const float inv = 1.0f / sqrtf(n2);
  for (int i = 0; i < 4; ++i) {
    filter->gyr_quat[i] = q[i] * inv;
  }
}

/* Low-pass the accelerometer in I, then turn the inclination quaternion so that the
 * filtered vector, seen in E6, points straight up. */
static void imu_filter_correct_inclination(imu_filter_t *const filter, const float acc_mps2[3]) {
  float acc_i[3];
  imu_filter_quat_rotate(filter->gyr_quat, acc_mps2, acc_i);
  imu_filter_lowpass_step(&filter->acc_filter, acc_i, filter->acc_lp, filter->acc_lp_rate, 3);
  if (filter->acc_time_s < IMU_FILTER_TIME_LIMIT_S) {
    filter->acc_time_s += filter->coeff.sample_period_s;
  }
  float a[3];
  imu_filter_quat_rotate(filter->acc_quat, filter->acc_lp, a);
  const float n2 = imu_filter_dot3(a, a);
  if (!(n2 > 1.0e-6f)) {
    return; /* no gravity to align with (free fall) */
  }
  const float inv = 1.0f / sqrtf(n2);
  const float ax = a[0] * inv;
  const float ay = a[1] * inv;
  filter->bias.correction_sum[0] += ax;
  filter->bias.correction_sum[1] += ay;
  /* shortest rotation taking the unit vector to +z: axis (ay, -ax, 0) */
  const float cw = sqrtf(0.5f + 0.5f * a[2] * inv);
  float corr[3] = {0.0f, 1.0f, 0.0f}; /* w, x, y; z is 0. Upside down: half turn about x */
  if (cw > 1.0e-6f) {
    const float k = 0.5f / cw;
    corr[0] = cw;
    corr[1] = k * ay;
    corr[2] = -k * ax;
  }
  const float *const p = filter->acc_quat;
  float q[4] = {corr[0] * p[0] - corr[1] * p[1] - corr[2] * p[2],
                corr[0] * p[1] + corr[1] * p[0] + corr[2] * p[3],
                corr[0] * p[2] - corr[1] * p[3] + corr[2] * p[0],
                corr[0] * p[3] + corr[1] * p[2] - corr[2] * p[1]};
  const float qinv = 1.0f / sqrtf(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (int i = 0; i < 4; ++i) {
    filter->acc_quat[i] = q[i] * qinv;
  }
}

void imu_filter_update(imu_filter_t *const filter, const float gyr_rads[3], const float acc_mps2[3],
                       const float *const mag_ut) {
  if (!filter->coeff.valid) {
    imu_filter_count(&filter->gyr_rejected);
    return;
  }
  if (filter->mag.steps_since_sample < UINT16_MAX) {
    ++filter->mag.steps_since_sample;
  }
  if (imu_filter_vector_ok(gyr_rads, IMU_FILTER_GYR_LIMIT_RADS)) {
    imu_filter_rest_gyr(filter, gyr_rads);
    imu_filter_integrate(filter, gyr_rads);
  } else {
    imu_filter_count(&filter->gyr_rejected);
  }
  if (imu_filter_vector_ok(acc_mps2, IMU_FILTER_ACC_LIMIT_MPS2)) {
    imu_filter_rest_acc(filter, acc_mps2);
    imu_filter_correct_inclination(filter, acc_mps2);
    imu_filter_bias_step(filter);
  } else {
    imu_filter_count(&filter->acc_rejected);
  }
  if (mag_ut != NULL) {
    if (imu_filter_vector_ok(mag_ut, IMU_FILTER_MAG_LIMIT_UT)) {
      imu_filter_mag_update(filter, mag_ut);
    } else {
      imu_filter_count(&filter->mag_rejected);
    }
  }
}

void imu_filter_quaternion_6d(const imu_filter_t *const filter, float q_wxyz[4]) {
  imu_filter_quat_6d(filter, q_wxyz);
}

void imu_filter_quaternion(const imu_filter_t *const filter, float q_wxyz[4]) {
  float q6[4];
  imu_filter_quat_6d(filter, q6);
  float s;
  float c;
  imu_filter_sincos(0.5f * filter->heading_rad, &s, &c);
  /* (c, 0, 0, s) ⊗ q6 */
  q_wxyz[0] = c * q6[0] - s * q6[3];
  q_wxyz[1] = c * q6[1] - s * q6[2];
  q_wxyz[2] = c * q6[2] + s * q6[1];
  q_wxyz[3] = c * q6[3] + s * q6[0];
}

bool imu_filter_mag_disturbed(const imu_filter_t *const filter) { return filter->mag.heading_held; }

bool imu_filter_settled(const imu_filter_t *const filter) {
  const float needed_s = filter->settings.acc_time_constant_s;
  return filter->coeff.valid && filter->acc_time_s >= needed_s &&
         (filter->mag.samples == 0u || filter->mag.time_s >= needed_s);
}

bool imu_filter_at_rest(const imu_filter_t *const filter) { return filter->rest.at_rest; }

void imu_filter_gyro_bias(const imu_filter_t *const filter, float bias_rads[3]) {
  for (int i = 0; i < 3; ++i) {
    bias_rads[i] = filter->bias.bias_rads[i];
  }
}

uint32_t imu_filter_rejected(const imu_filter_t *const filter) {
  const uint64_t total =
      (uint64_t)filter->gyr_rejected + filter->acc_rejected + filter->mag_rejected;
  return total > UINT32_MAX ? UINT32_MAX : (uint32_t)total;
}
