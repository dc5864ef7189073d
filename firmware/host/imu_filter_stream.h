/* Host-only streaming entry points of the orientation filter, for Python (ctypes,
 * mocap_edge.hub.i2c.filter): one call per sample on a caller-owned imu_filter_t, which
 * Python allocates as imu_filter_stream_state_size() bytes. */
#ifndef FIRMWARE_HOST_IMU_FILTER_STREAM_H
#define FIRMWARE_HOST_IMU_FILTER_STREAM_H

#include <stddef.h>
#include <stdint.h>

#include "imu_filter.h"

/* sizeof(imu_filter_t): the bytes Python allocates for the state. */
size_t imu_filter_stream_state_size(void);

/* Starts `filter` with `settings` (NULL: imu_filter_settings_default) at `sample_period_s`.
 * Returns 0, or -1 when the settings or the period are invalid (the filter then refuses
 * every sample). */
int imu_filter_stream_init(imu_filter_t *const filter, const imu_filter_settings_t *const settings,
                           float sample_period_s);

/* One sample (gyr rad/s, acc m/s^2, mag uT or NULL; sensor frame): writes the orientation
 * w, x, y, z (sensor -> ENU; 6D: heading from the gyroscope) into q_wxyz and returns the
 * flags IMU_FILTER_BATCH_* (imu_filter_batch.h). */
uint8_t imu_filter_stream_update(imu_filter_t *const filter, const float gyr_rads[3],
                                 const float acc_mps2[3], const float *const mag_ut,
                                 float q_wxyz[4]);

#endif /* FIRMWARE_HOST_IMU_FILTER_STREAM_H */
