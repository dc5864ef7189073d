/* Heading correction of the orientation filter (imu_filter.h) from the magnetometer.
 *
 * The field seen in E6 gives the heading error atan2(east, north) - heading; the heading
 * follows it with mag_time_constant_s (its first seconds are a running average, so the
 * start converges at once). The field's norm and dip (angle below the horizon), low-passed,
 * are compared with a reference: outside the thresholds the field is disturbed (a magnet,
 * steel) and the heading is held on the gyroscope, for at most mag_max_rejection_time_s.
 * The reference adapts slowly while undisturbed; a different field that stays steady
 * while the sensor turns (so not a local disturbance) for mag_new_time_s becomes the new
 * reference, which is also how the first reference is learned. */
#include "imu_filter_internal.h"
#include "imu_filter_math.h"

#define IMU_FILTER_MAG_MIN_NORM_UT 1.0e-3f /* below: no field measured (skip) */

static float imu_filter_at_most_one(float gain) { return gain < 1.0f ? gain : 1.0f; }

void imu_filter_mag_init(imu_filter_t *const filter) {
  imu_filter_mag_t *const mag = &filter->mag;
  mag->candidate_norm_ut = -1.0f;
  mag->disturbed = true;
  mag->init_gain = 1.0f;
}

static bool imu_filter_mag_matches(const imu_filter_t *const filter, float norm_ut, float dip_rad) {
  const imu_filter_mag_t *const mag = &filter->mag;
  return fabsf(mag->norm_dip[0] - norm_ut) < filter->settings.mag_norm_threshold * norm_ut &&
         fabsf(mag->norm_dip[1] - dip_rad) < filter->settings.mag_dip_threshold_rad;
}

/* Disturbance detection and reference learning from the low-passed norm and dip. */
static void imu_filter_mag_disturbance(imu_filter_t *const filter, float dt_s, float ref_gain) {
  const imu_filter_settings_t *const s = &filter->settings;
  imu_filter_mag_t *const mag = &filter->mag;
  if (imu_filter_mag_matches(filter, mag->ref_norm_ut, mag->ref_dip_rad)) {
    mag->undisturbed_time_s += dt_s;
    if (mag->undisturbed_time_s >= s->mag_min_undisturbed_time_s) {
      mag->disturbed = false;
      mag->ref_norm_ut += ref_gain * (mag->norm_dip[0] - mag->ref_norm_ut);
      mag->ref_dip_rad += ref_gain * (mag->norm_dip[1] - mag->ref_dip_rad);
    }
  } else {
    mag->undisturbed_time_s = 0.0f;
    mag->disturbed = true;
  }
  if (!imu_filter_mag_matches(filter, mag->candidate_norm_ut, mag->candidate_dip_rad)) {
    mag->candidate_time_s = 0.0f;
    mag->candidate_norm_ut = mag->norm_dip[0];
    mag->candidate_dip_rad = mag->norm_dip[1];
    return;
  }
  const float min_gyr = s->mag_new_min_gyr_rads;
  if (imu_filter_dot3(filter->rest.gyr_lp, filter->rest.gyr_lp) >= min_gyr * min_gyr) {
    mag->candidate_time_s += dt_s;
  }
  mag->candidate_norm_ut += ref_gain * (mag->norm_dip[0] - mag->candidate_norm_ut);
  mag->candidate_dip_rad += ref_gain * (mag->norm_dip[1] - mag->candidate_dip_rad);
  const bool first = mag->ref_norm_ut == 0.0f;
  if (mag->disturbed && (mag->candidate_time_s >= s->mag_new_time_s ||
                         (first && mag->candidate_time_s >= s->mag_new_first_time_s))) {
    mag->ref_norm_ut = mag->candidate_norm_ut;
    mag->ref_dip_rad = mag->candidate_dip_rad;
    mag->disturbed = false;
    mag->undisturbed_time_s = s->mag_min_undisturbed_time_s;
  }
}

/* Heading gain of this sample: 0 while a disturbance is held, the start's running average. */
static float imu_filter_mag_heading_gain(imu_filter_t *const filter, float dt_s, float base_gain) {
  const imu_filter_settings_t *const s = &filter->settings;
  imu_filter_mag_t *const mag = &filter->mag;
  float k = base_gain;
  mag->heading_held = false;
  if (s->mag_rejection_enabled) {
    if (mag->disturbed) {
      if (mag->rejection_time_s <= s->mag_max_rejection_time_s) {
        mag->rejection_time_s += dt_s;
        mag->heading_held = true;
        k = 0.0f;
      } else {
        k = base_gain / s->mag_rejection_factor;
      }
    } else {
      mag->rejection_time_s -= s->mag_rejection_factor * dt_s;
      mag->rejection_time_s = mag->rejection_time_s > 0.0f ? mag->rejection_time_s : 0.0f;
    }
  }
  if (mag->init_gain > 0.0f) {
    if (k < mag->init_gain) {
      k = mag->init_gain;
      mag->heading_held = false;
    }
    mag->init_gain = mag->init_gain / (mag->init_gain + 1.0f); /* 1, 1/2, 1/3, ... */
    if (mag->init_gain < base_gain) {
      mag->init_gain = 0.0f;
    }
  }
  return k;
}

/* Low-pass of the field's norm and dip over `steps` IMU samples (the first sets it). */
static void imu_filter_mag_norm_dip(imu_filter_t *const filter, const float norm_dip[2],
                                    float steps) {
  imu_filter_mag_t *const mag = &filter->mag;
  const float gain =
      mag->samples == 0u ? 1.0f : imu_filter_at_most_one(steps * filter->coeff.mag_current_gain);
  for (int i = 0; i < 2; ++i) {
    mag->norm_dip_lp1[i] += gain * (norm_dip[i] - mag->norm_dip_lp1[i]);
    mag->norm_dip[i] += gain * (mag->norm_dip_lp1[i] - mag->norm_dip[i]);
  }
  ++mag->samples;
}

void imu_filter_mag_update(imu_filter_t *const filter, const float mag_ut[3]) {
  imu_filter_mag_t *const mag = &filter->mag;
  float q[4];
  imu_filter_quat_6d(filter, q);
  float m[3];
  imu_filter_quat_rotate(q, mag_ut, m);
  const float horizontal = sqrtf(m[0] * m[0] + m[1] * m[1]);
  const float norm_dip[2] = {sqrtf(horizontal * horizontal + m[2] * m[2]),
                             imu_filter_atan2(-m[2], horizontal)};
  if (!(norm_dip[0] > IMU_FILTER_MAG_MIN_NORM_UT)) {
    return; /* no field: not a reading (its time counts toward the next one) */
  }
  /* time since the last reading: a magnetometer slower than the IMU passes NULL between */
  const float steps = (float)mag->steps_since_sample;
  mag->steps_since_sample = 0u;
  const float dt_s = steps * filter->coeff.sample_period_s;
  if (mag->time_s < 1.0e6f) {
    mag->time_s += dt_s;
  }
  imu_filter_mag_norm_dip(filter, norm_dip, steps);
  if (filter->settings.mag_rejection_enabled) {
    imu_filter_mag_disturbance(filter, dt_s,
                               imu_filter_at_most_one(steps * filter->coeff.mag_ref_gain));
  }
  const float error = imu_filter_wrap_angle(imu_filter_atan2(m[0], m[1]) - filter->heading_rad);
  const float k = imu_filter_mag_heading_gain(
      filter, dt_s, imu_filter_at_most_one(steps * filter->coeff.mag_gain));
  filter->heading_rad = imu_filter_wrap_angle(filter->heading_rad + k * error);
}
