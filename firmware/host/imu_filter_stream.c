/* Host-only streaming runner of the orientation filter (imu_filter_stream.h). */
#include "imu_filter_stream.h"

#include "imu_filter_batch.h"

size_t imu_filter_stream_state_size(void) { return sizeof(imu_filter_t); }

int imu_filter_stream_init(imu_filter_t *const filter, const imu_filter_settings_t *const settings,
                           float sample_period_s) {
  const imu_filter_settings_t *const used =
      settings != NULL ? settings : &imu_filter_settings_default;
  imu_filter_init(filter, used, sample_period_s);
  return imu_filter_settings_valid(used, sample_period_s) ? 0 : -1;
}

uint8_t imu_filter_stream_update(imu_filter_t *const filter, const float gyr_rads[3],
                                 const float acc_mps2[3], const float *const mag_ut,
                                 float q_wxyz[4]) {
  imu_filter_update(filter, gyr_rads, acc_mps2, mag_ut);
  imu_filter_quaternion(filter, q_wxyz);
  return (uint8_t)((imu_filter_at_rest(filter) ? IMU_FILTER_BATCH_REST : 0u) |
                   (imu_filter_mag_disturbed(filter) ? IMU_FILTER_BATCH_HELD : 0u) |
                   (imu_filter_settled(filter) ? IMU_FILTER_BATCH_SETTLED : 0u));
}
