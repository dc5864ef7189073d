/* Rest detection and gyroscope bias estimation of the orientation filter (imu_filter.h).
 *
 * At rest, the low-passed gyroscope is the bias. In motion, the inclination corrections
 * are the measurement: a residual bias b turns the strapdown frame at R b (R: sensor to
 * E6), and the corrections undo that turning after the accelerometer low-pass. Low-passing
 * R and R b with the same filter makes the measurement linear in b:
 *   LP(R) b  =  -(horizontal corrections per second) + LP(R b_estimate)   (x, y of E6)
 * A 3-state Kalman filter weighs it; the vertical (heading) component, unobservable here,
 * is softly pulled to zero. It runs every bias_decimation samples (about
 * bias_update_rate_hz), which keeps the per-sample cost low; the bias drifts slowly. */
#include <string.h>

#include "imu_filter_internal.h"
#include "imu_filter_math.h"

void imu_filter_bias_init(imu_filter_t *const filter) {
  const imu_filter_settings_t *const s = &filter->settings;
  imu_filter_coefficients_t *const c = &filter->coeff;
  imu_filter_bias_t *const bias = &filter->bias;
  /* Variances as a Kalman filter with random-walk bias: growth v per step makes the
   * steady variance p_motion in motion and p_rest at rest for measurement variance w. */
  const float forget = 0.1f * IMU_FILTER_PI / 180.0f; /* rad/s per forgetting time */
  c->bias_p0 = s->bias_sigma_init_rads * s->bias_sigma_init_rads;
  c->bias_v = forget * forget * c->bias_period_s / s->bias_forgetting_time_s;
  const float p_motion = s->bias_sigma_motion_rads * s->bias_sigma_motion_rads;
  const float p_rest = s->bias_sigma_rest_rads * s->bias_sigma_rest_rads;
  c->bias_w_motion = p_motion * p_motion / c->bias_v + p_motion;
  c->bias_w_vertical = c->bias_w_motion / s->bias_vertical_forgetting;
  c->bias_w_rest = p_rest * p_rest / c->bias_v + p_rest;
  bias->p[0] = bias->p[3] = bias->p[5] = c->bias_p0;
  imu_filter_lowpass_init(&bias->r_filter, c->bias_period_s, s->acc_time_constant_s,
                          s->acc_damping);
  const float period_s = c->sample_period_s;
  imu_filter_lowpass_init(&filter->rest.gyr_filter, period_s, s->rest_filter_time_constant_s, 1.0f);
  imu_filter_lowpass_init(&filter->rest.acc_filter, period_s, s->rest_filter_time_constant_s, 1.0f);
}

void imu_filter_rest_gyr(imu_filter_t *const filter, const float gyr_rads[3]) {
  imu_filter_rest_t *const rest = &filter->rest;
  imu_filter_lowpass_step(&rest->gyr_filter, gyr_rads, rest->gyr_lp, rest->gyr_lp_rate, 3);
  const float d[3] = {gyr_rads[0] - rest->gyr_lp[0], gyr_rads[1] - rest->gyr_lp[1],
                      gyr_rads[2] - rest->gyr_lp[2]};
  const float limit = filter->settings.bias_limit_rads;
  rest->gyr_still = imu_filter_dot3(d, d) < filter->coeff.rest_gyr_threshold2 &&
                    imu_filter_vector_ok(rest->gyr_lp, limit);
}

void imu_filter_rest_acc(imu_filter_t *const filter, const float acc_mps2[3]) {
  imu_filter_rest_t *const rest = &filter->rest;
  imu_filter_lowpass_step(&rest->acc_filter, acc_mps2, rest->acc_lp, rest->acc_lp_rate, 3);
  const float d[3] = {acc_mps2[0] - rest->acc_lp[0], acc_mps2[1] - rest->acc_lp[1],
                      acc_mps2[2] - rest->acc_lp[2]};
  if (rest->gyr_still && imu_filter_dot3(d, d) < filter->coeff.rest_acc_threshold2) {
    if (rest->still_time_s < filter->settings.rest_time_s) {
      rest->still_time_s += filter->coeff.sample_period_s;
    }
    rest->at_rest = rest->still_time_s >= filter->settings.rest_time_s;
  } else {
    rest->still_time_s = 0.0f;
    rest->at_rest = false;
  }
}

static float imu_filter_clip(float value, float limit) {
  return value > limit ? limit : value < -limit ? -limit : value;
}

/* Kalman update of the bias with measurement error e = y - H b (H 3x3 row-major, W diagonal),
 * the covariance kept symmetric (6 values). */
static void imu_filter_bias_kalman(imu_filter_bias_t *const bias, const float h[9],
                                   const float e[3], const float w[3]) {
  const float *const p = bias->p;
  const float pm[9] = {p[0], p[1], p[2], p[1], p[3], p[4], p[2], p[4], p[5]};
  float hp[9]; /* H P */
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      hp[3 * i + j] = h[3 * i] * pm[j] + h[3 * i + 1] * pm[3 + j] + h[3 * i + 2] * pm[6 + j];
    }
  }
  /* S = H P H^T + W, symmetric */
  float s[6];
  const int rows[6] = {0, 0, 0, 1, 1, 2};
  const int cols[6] = {0, 1, 2, 1, 2, 2};
  for (int k = 0; k < 6; ++k) {
    const int i = rows[k];
    const int j = cols[k];
    s[k] = hp[3 * i] * h[3 * j] + hp[3 * i + 1] * h[3 * j + 1] + hp[3 * i + 2] * h[3 * j + 2];
  }
  s[0] += w[0];
  s[3] += w[1];
  s[5] += w[2];
  /* S^-1 by cofactors */
  const float c00 = s[3] * s[5] - s[4] * s[4];
  const float c01 = s[2] * s[4] - s[1] * s[5];
  const float c02 = s[1] * s[4] - s[2] * s[3];
  const float det = s[0] * c00 + s[1] * c01 + s[2] * c02;
  if (!(det > 0.0f)) {
    return;
  }
  const float inv_det = 1.0f / det;
  const float si[9] = {c00 * inv_det,
                       c01 * inv_det,
                       c02 * inv_det,
                       c01 * inv_det,
                       (s[0] * s[5] - s[2] * s[2]) * inv_det,
                       (s[1] * s[2] - s[0] * s[4]) * inv_det,
                       c02 * inv_det,
                       (s[1] * s[2] - s[0] * s[4]) * inv_det,
                       (s[0] * s[3] - s[1] * s[1]) * inv_det};
  float k[9]; /* K = (H P)^T S^-1 */
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      k[3 * i + j] = hp[i] * si[j] + hp[3 + i] * si[3 + j] + hp[6 + i] * si[6 + j];
    }
  }
  for (int i = 0; i < 3; ++i) {
    bias->bias_rads[i] += k[3 * i] * e[0] + k[3 * i + 1] * e[1] + k[3 * i + 2] * e[2];
  }
  /* P -= K H P */
  for (int m = 0; m < 6; ++m) {
    const int i = rows[m];
    const int j = cols[m];
    bias->p[m] -= k[3 * i] * hp[j] + k[3 * i + 1] * hp[3 + j] + k[3 * i + 2] * hp[6 + j];
  }
}

/* Low-pass R(S->E6) and R b for the motion measurement. */
static void imu_filter_bias_track_rotation(imu_filter_t *const filter) {
  float q[4];
  imu_filter_quat_6d(filter, q);
  const float *const b = filter->bias.bias_rads;
  float x[11];
  x[0] = 1.0f - 2.0f * (q[2] * q[2] + q[3] * q[3]);
  x[1] = 2.0f * (q[1] * q[2] - q[0] * q[3]);
  x[2] = 2.0f * (q[1] * q[3] + q[0] * q[2]);
  x[3] = 2.0f * (q[1] * q[2] + q[0] * q[3]);
  x[4] = 1.0f - 2.0f * (q[1] * q[1] + q[3] * q[3]);
  x[5] = 2.0f * (q[2] * q[3] - q[0] * q[1]);
  x[6] = 2.0f * (q[1] * q[3] - q[0] * q[2]);
  x[7] = 2.0f * (q[2] * q[3] + q[0] * q[1]);
  x[8] = 1.0f - 2.0f * (q[1] * q[1] + q[2] * q[2]);
  x[9] = x[0] * b[0] + x[1] * b[1] + x[2] * b[2];
  x[10] = x[3] * b[0] + x[4] * b[1] + x[5] * b[2];
  imu_filter_bias_t *const bias = &filter->bias;
  imu_filter_lowpass_step(&bias->r_filter, x, bias->r_lp, bias->r_lp_rate, 11);
}

void imu_filter_bias_step(imu_filter_t *const filter) {
  const imu_filter_settings_t *const s = &filter->settings;
  const imu_filter_coefficients_t *const c = &filter->coeff;
  imu_filter_bias_t *const bias = &filter->bias;
  if (++bias->phase < c->bias_decimation || !(s->motion_bias_enabled || s->rest_bias_enabled)) {
    return;
  }
  bias->phase = 0u;
  imu_filter_bias_track_rotation(filter);
  const float corr_x = bias->correction_sum[0];
  const float corr_y = bias->correction_sum[1];
  bias->correction_sum[0] = bias->correction_sum[1] = 0.0f;
  static const int diagonal[3] = {0, 3, 5};
  for (int i = 0; i < 3; ++i) {
    if (bias->p[diagonal[i]] < c->bias_p0) {
      bias->p[diagonal[i]] += c->bias_v;
    }
  }
  const float *const b = bias->bias_rads;
  float e[3];
  if (filter->rest.at_rest && s->rest_bias_enabled) {
    static const float identity[9] = {1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f};
    const float w[3] = {c->bias_w_rest, c->bias_w_rest, c->bias_w_rest};
    for (int i = 0; i < 3; ++i) {
      e[i] = imu_filter_clip(filter->rest.gyr_lp[i] - b[i], s->bias_limit_rads);
    }
    imu_filter_bias_kalman(bias, identity, e, w);
  } else if (s->motion_bias_enabled) {
    const float *const r = bias->r_lp;
    const float per_s = 1.0f / c->bias_period_s;
    e[0] = -corr_y * per_s + r[9] - (r[0] * b[0] + r[1] * b[1] + r[2] * b[2]);
    e[1] = corr_x * per_s + r[10] - (r[3] * b[0] + r[4] * b[1] + r[5] * b[2]);
    e[2] = -(r[6] * b[0] + r[7] * b[1] + r[8] * b[2]);
    for (int i = 0; i < 3; ++i) {
      e[i] = imu_filter_clip(e[i], s->bias_limit_rads);
    }
    const float w[3] = {c->bias_w_motion, c->bias_w_motion, c->bias_w_vertical};
    imu_filter_bias_kalman(bias, r, e, w);
  }
  for (int i = 0; i < 3; ++i) {
    bias->bias_rads[i] = imu_filter_clip(bias->bias_rads[i], s->bias_limit_rads);
  }
}
