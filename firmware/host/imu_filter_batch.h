/* Host-only batch entry points of the orientation filter, for Python (ctypes,
 * mocap.imu_node.filter): one call runs the filter over a whole recording. */
#ifndef FIRMWARE_HOST_IMU_FILTER_BATCH_H
#define FIRMWARE_HOST_IMU_FILTER_BATCH_H

#include <stddef.h>
#include <stdint.h>

#include "imu_filter.h"

/* Bits of imu_filter_batch_run's flags_out. */
#define IMU_FILTER_BATCH_REST 0x01u    /* imu_filter_at_rest */
#define IMU_FILTER_BATCH_HELD 0x02u    /* imu_filter_mag_disturbed (heading held) */
#define IMU_FILTER_BATCH_SETTLED 0x04u /* imu_filter_settled */

/* sizeof(imu_filter_settings_t) and sizeof(imu_filter_t): Python checks its mirror. */
size_t imu_filter_batch_settings_size(void);
size_t imu_filter_batch_state_size(void);

/* Copies the default settings into `settings`. */
void imu_filter_batch_default_settings(imu_filter_settings_t *const settings);

/* Runs a fresh filter over n samples (row-major n x 3 arrays; gyr rad/s, acc m/s^2, mag uT
 * or NULL for 6D; a row with NaN is skipped by the filter as bad input). Writes q_out
 * (n x 4, sensor -> ENU; 6D: heading from the gyroscope) and, when not NULL, q6_out (n x 4,
 * sensor -> E6), bias_out (n x 3, rad/s) and flags_out (n, IMU_FILTER_BATCH_*).
 * Returns the number of vectors the filter rejected, or -1 when the settings or the
 * period are invalid (nothing written). */
int64_t imu_filter_batch_run(const imu_filter_settings_t *const settings, float sample_period_s,
                             const float *const gyr, const float *const acc, const float *const mag,
                             size_t n, float *const q_out, float *const q6_out,
                             float *const bias_out, uint8_t *const flags_out);

#endif /* FIRMWARE_HOST_IMU_FILTER_BATCH_H */
