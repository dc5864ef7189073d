/* ICM-42688-P self-test: the datasheet procedure with the factory trim codes (the
 * criteria of TDK's reference driver for the ICM-426xx family).
 *
 * At +-250 deg/s and +-2 g (the ranges the trim codes refer to), 1 kHz: the mean of
 * ICM42688_SELF_TEST_SAMPLES samples with the actuation off, then with the gyroscope's,
 * then with the accelerometer's on. Response = |on - off| per axis, in LSB. Factory
 * response of trim code c: 2620 * 1.01^(c - 1) LSB.
 */
#include <math.h>

#include "icm42688.h"
#include "icm42688_internal.h"
#include "icm42688_regs.h"

#define ICM42688_ST_GYRO_SETTLE_US 200000u /* actuation on to a stable response */
#define ICM42688_ST_ACCEL_SETTLE_US 25000u
#define ICM42688_ST_RATIO_MIN 0.5f
#define ICM42688_ST_RATIO_MAX 1.5f
#define ICM42688_ST_TRIM_BASE_LSB 2620.0f
#define ICM42688_ST_GYRO_LSB_PER_DPS (32768.0f / 250.0f)
#define ICM42688_ST_ACCEL_LSB_PER_G (32768.0f / 2.0f)
#define ICM42688_ST_GYRO_MIN_DPS 60.0f /* without trim codes */
#define ICM42688_ST_GYRO_MAX_OFFSET_DPS 20.0f
#define ICM42688_ST_ACCEL_MIN_G 0.05f /* without trim codes */
#define ICM42688_ST_ACCEL_MAX_G 1.2f

static const icm42688_config_t icm42688_self_test_config = {
    .odr_hz = 1000u, .acc_range_g = 2u, .gyro_range_dps = 250u, .fifo_watermark_samples = 1u};

/* Means of accel x y z, gyro x y z over the self-test sample count, in LSB. */
static icm42688_status_t icm42688_average(icm42688_t *const dev, float mean[6]) {
  int32_t sum[6] = {0, 0, 0, 0, 0, 0};
  for (uint32_t n = 0u; n < ICM42688_SELF_TEST_SAMPLES; ++n) {
    int16_t raw[6];
    const icm42688_status_t status = icm42688_read_raw_when_ready(dev, raw);
    if (status != ICM42688_OK) return status;
    for (size_t i = 0; i < 6u; ++i) sum[i] += raw[i];
  }
  for (size_t i = 0; i < 6u; ++i) mean[i] = (float)sum[i] / (float)ICM42688_SELF_TEST_SAMPLES;
  return ICM42688_OK;
}

/* Actuation `enable` on, settle, average into `mean`, actuation off. */
static icm42688_status_t icm42688_average_actuated(icm42688_t *const dev, uint8_t enable,
                                                   uint32_t settle_us, float mean[6]) {
  icm42688_status_t status =
      icm42688_write_register(dev, 0u, ICM42688_REG_SELF_TEST_CONFIG, enable);
  if (status != ICM42688_OK) return status;
  icm42688_wait_us(dev, settle_us);
  status = icm42688_average(dev, mean);
  if (status != ICM42688_OK) return status;
  return icm42688_write_register(dev, 0u, ICM42688_REG_SELF_TEST_CONFIG, 0u);
}

/* One axis: the response against its trim code (or the absolute limits without one). */
static bool icm42688_axis_passes(float response_lsb, uint8_t code, float min_lsb, float max_lsb) {
  if (code == 0u) return response_lsb >= min_lsb && response_lsb <= max_lsb;
  const float factory_lsb = ICM42688_ST_TRIM_BASE_LSB * powf(1.01f, (float)code - 1.0f);
  const float ratio = response_lsb / factory_lsb;
  return ratio > ICM42688_ST_RATIO_MIN && ratio < ICM42688_ST_RATIO_MAX;
}

typedef struct {
  float off[6]; /* accel x y z, gyro x y z, LSB */
  float gyro_on[6];
  float accel_on[6];
  uint8_t gyro_codes[3];
  uint8_t accel_codes[3];
} icm42688_self_test_data_t;

static bool icm42688_evaluate(const icm42688_self_test_data_t *const data) {
  bool passed = true;
  for (size_t axis = 0; axis < 3u; ++axis) {
    const float gyro_response = fabsf(data->gyro_on[3u + axis] - data->off[3u + axis]);
    const float accel_response = fabsf(data->accel_on[axis] - data->off[axis]);
    passed = passed && icm42688_axis_passes(gyro_response, data->gyro_codes[axis],
                                            ICM42688_ST_GYRO_MIN_DPS * ICM42688_ST_GYRO_LSB_PER_DPS,
                                            65536.0f);
    passed = passed && icm42688_axis_passes(accel_response, data->accel_codes[axis],
                                            ICM42688_ST_ACCEL_MIN_G * ICM42688_ST_ACCEL_LSB_PER_G,
                                            ICM42688_ST_ACCEL_MAX_G * ICM42688_ST_ACCEL_LSB_PER_G);
    passed = passed && fabsf(data->off[3u + axis]) <
                           ICM42688_ST_GYRO_MAX_OFFSET_DPS * ICM42688_ST_GYRO_LSB_PER_DPS;
  }
  return passed;
}

static icm42688_status_t icm42688_measure(icm42688_t *const dev,
                                          icm42688_self_test_data_t *const data) {
  icm42688_status_t status = icm42688_configure(dev, &icm42688_self_test_config);
  /* The data registers only: no FIFO, no INT1 edge for the node meanwhile. */
  if (status == ICM42688_OK)
    status = icm42688_write_register(dev, 0u, ICM42688_REG_INT_SOURCE0, 0u);
  if (status == ICM42688_OK) {
    status =
        icm42688_write_register(dev, 0u, ICM42688_REG_FIFO_CONFIG, ICM42688_FIFO_CONFIG_BYPASS);
  }
  if (status == ICM42688_OK) status = icm42688_average(dev, data->off);
  if (status == ICM42688_OK) {
    status = icm42688_average_actuated(dev, ICM42688_SELF_TEST_GYRO_XYZ, ICM42688_ST_GYRO_SETTLE_US,
                                       data->gyro_on);
  }
  if (status == ICM42688_OK) {
    status = icm42688_average_actuated(
        dev, ICM42688_SELF_TEST_ACCEL_XYZ | ICM42688_SELF_TEST_ACCEL_POWER,
        ICM42688_ST_ACCEL_SETTLE_US, data->accel_on);
  }
  if (status == ICM42688_OK) {
    status = icm42688_read_registers(dev, 1u, ICM42688_REG_XG_ST_DATA, data->gyro_codes, 3u);
  }
  if (status == ICM42688_OK) {
    status = icm42688_read_registers(dev, 2u, ICM42688_REG_XA_ST_DATA, data->accel_codes, 3u);
  }
  return status;
}

icm42688_status_t icm42688_self_test(icm42688_t *const dev, bool *const passed) {
  *passed = false;
  if (!dev->initialised) return ICM42688_NOT_READY;
  const bool was_configured = dev->configured;
  const icm42688_config_t previous = dev->config;
  icm42688_self_test_data_t data;
  icm42688_status_t status = icm42688_measure(dev, &data);
  if (status == ICM42688_OK) *passed = icm42688_evaluate(&data);
  if (status == ICM42688_OK && was_configured) status = icm42688_configure(dev, &previous);
  if (status == ICM42688_OK && !was_configured) {
    dev->configured = false; /* sensors on, FIFO off: icm42688_configure starts it */
    dev->config = previous;
  }
  dev->last_status = status;
  return status;
}
