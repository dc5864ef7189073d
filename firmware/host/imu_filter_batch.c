/* Host-only batch runner of the orientation filter (imu_filter_batch.h). */
#include "imu_filter_batch.h"

size_t imu_filter_batch_settings_size(void) { return sizeof(imu_filter_settings_t); }

size_t imu_filter_batch_state_size(void) { return sizeof(imu_filter_t); }

void imu_filter_batch_default_settings(imu_filter_settings_t *const settings) {
  *settings = imu_filter_settings_default;
}

static void imu_filter_batch_outputs(const imu_filter_t *const filter, size_t i,
                                     float *const q6_out, float *const bias_out,
                                     uint8_t *const flags_out) {
  if (q6_out != NULL) {
    imu_filter_quaternion_6d(filter, &q6_out[4 * i]);
  }
  if (bias_out != NULL) {
    imu_filter_gyro_bias(filter, &bias_out[3 * i]);
  }
  if (flags_out != NULL) {
    flags_out[i] = (uint8_t)((imu_filter_at_rest(filter) ? IMU_FILTER_BATCH_REST : 0u) |
                             (imu_filter_mag_disturbed(filter) ? IMU_FILTER_BATCH_HELD : 0u) |
                             (imu_filter_settled(filter) ? IMU_FILTER_BATCH_SETTLED : 0u));
  }
}

int64_t imu_filter_batch_run(const imu_filter_settings_t *const settings, float sample_period_s,
                             const float *const gyr, const float *const acc, const float *const mag,
                             size_t n, float *const q_out, float *const q6_out,
                             float *const bias_out, uint8_t *const flags_out) {
  if (!imu_filter_settings_valid(settings, sample_period_s) || gyr == NULL || acc == NULL ||
      q_out == NULL) {
    return -1;
  }
  imu_filter_t filter;
  imu_filter_init(&filter, settings, sample_period_s);
  for (size_t i = 0; i < n; ++i) {
    imu_filter_update(&filter, &gyr[3 * i], &acc[3 * i], mag != NULL ? &mag[3 * i] : NULL);
    imu_filter_quaternion(&filter, &q_out[4 * i]);
    imu_filter_batch_outputs(&filter, i, q6_out, bias_out, flags_out);
  }
  return (int64_t)imu_filter_rejected(&filter);
}
