/* ICM-42688-P: bus access, reset and identification, configuration, unit conversion. */
#include "icm42688.h"

#include <string.h>

#include "icm42688_internal.h"
#include "icm42688_regs.h"

#define ICM42688_RESET_WAIT_US 1000u  /* soft reset to first access (datasheet: 1 ms) */
#define ICM42688_POWER_WAIT_US 200u   /* PWR_MGMT0 change to the next write */
#define ICM42688_GYRO_START_US 60000u /* gyroscope start-up before its data is valid */
#define ICM42688_STANDARD_GRAVITY_MPS2 9.80665f
#define ICM42688_RAD_PER_DEG 0.017453292519943295f
#define ICM42688_FULL_SCALE_LSB 32768.0f
#define ICM42688_CLIP_LSB 32767

const icm42688_config_t icm42688_config_default = {
    .odr_hz = 1000u, .acc_range_g = 16u, .gyro_range_dps = 2000u, .fifo_watermark_samples = 10u};

typedef struct {
  uint16_t hz;
  uint8_t code; /* GYRO_CONFIG0 / ACCEL_CONFIG0 ODR field */
  uint32_t period_us;
} icm42688_odr_entry_t;

static const icm42688_odr_entry_t icm42688_odr_table[] = {
    {25u, ICM42688_ODR_25HZ, 40000u},   {50u, ICM42688_ODR_50HZ, 20000u},
    {100u, ICM42688_ODR_100HZ, 10000u}, {200u, ICM42688_ODR_200HZ, 5000u},
    {500u, ICM42688_ODR_500HZ, 2000u},  {1000u, ICM42688_ODR_1KHZ, 1000u},
    {2000u, ICM42688_ODR_2KHZ, 500u},   {4000u, ICM42688_ODR_4KHZ, 250u},
    {8000u, ICM42688_ODR_8KHZ, 125u},
};
#define ICM42688_ODR_COUNT (sizeof(icm42688_odr_table) / sizeof(icm42688_odr_table[0]))

static const icm42688_odr_entry_t *icm42688_odr_find(uint16_t odr_hz) {
  for (size_t i = 0; i < ICM42688_ODR_COUNT; ++i) {
    if (icm42688_odr_table[i].hz == odr_hz) return &icm42688_odr_table[i];
  }
  return NULL;
}

bool icm42688_odr_supported(uint16_t odr_hz) { return icm42688_odr_find(odr_hz) != NULL; }

uint32_t icm42688_odr_period_us(uint16_t odr_hz) {
  const icm42688_odr_entry_t *const entry = icm42688_odr_find(odr_hz);
  return entry != NULL ? entry->period_us : 0u;
}

/* FS_SEL of a full scale (accelerometer: 16 g = 0 .. 2 g = 3; gyroscope: 2000 deg/s = 0
 * .. 250 deg/s = 3); -1 outside the table. */
static int icm42688_fs_select(uint16_t range, uint16_t largest) {
  for (int select = 0; select < 4; ++select) {
    if (range == (uint16_t)(largest >> select)) return select;
  }
  return -1;
}

static icm42688_status_t icm42688_failed(icm42688_t *const dev, bus_status_t status) {
  dev->initialised = false;
  dev->configured = false;
  dev->bank = ICM42688_BANK_UNKNOWN;
  dev->bus_failures++;
  dev->last_status = status == BUS_NACK ? ICM42688_NACK : ICM42688_BUS_ERROR;
  return dev->last_status;
}

static icm42688_status_t icm42688_select_bank(icm42688_t *const dev, uint8_t bank) {
  if (dev->bank == bank) return ICM42688_OK;
  const bus_status_t status =
      dev->bus->write(dev->bus->context, dev->address, ICM42688_REG_BANK_SEL, &bank, 1u);
  if (status != BUS_OK) return icm42688_failed(dev, status);
  dev->bank = bank;
  return ICM42688_OK;
}

icm42688_status_t icm42688_read_registers(icm42688_t *const dev, uint8_t bank, uint8_t reg,
                                          uint8_t *const data, size_t length) {
  const icm42688_status_t selected = icm42688_select_bank(dev, bank);
  if (selected != ICM42688_OK) return selected;
  const bus_status_t status = dev->bus->read(dev->bus->context, dev->address, reg, data, length);
  return status == BUS_OK ? ICM42688_OK : icm42688_failed(dev, status);
}

icm42688_status_t icm42688_write_register(icm42688_t *const dev, uint8_t bank, uint8_t reg,
                                          uint8_t value) {
  const icm42688_status_t selected = icm42688_select_bank(dev, bank);
  if (selected != ICM42688_OK) return selected;
  const bus_status_t status = dev->bus->write(dev->bus->context, dev->address, reg, &value, 1u);
  return status == BUS_OK ? ICM42688_OK : icm42688_failed(dev, status);
}

void icm42688_wait_us(const icm42688_t *const dev, uint32_t microseconds) {
  if (dev->bus->delay_us != NULL) dev->bus->delay_us(dev->bus->context, microseconds);
}

static uint32_t icm42688_now(const icm42688_t *const dev) {
  return dev->bus->now_us != NULL ? dev->bus->now_us(dev->bus->context) : 0u;
}

icm42688_status_t icm42688_poll_int_status(icm42688_t *const dev) {
  uint8_t status = 0u;
  const icm42688_status_t result =
      icm42688_read_registers(dev, 0u, ICM42688_REG_INT_STATUS, &status, 1u);
  dev->int_status |= status;
  return result;
}

icm42688_status_t icm42688_flush_fifo(icm42688_t *const dev) {
  const icm42688_status_t status = icm42688_write_register(dev, 0u, ICM42688_REG_SIGNAL_PATH_RESET,
                                                           ICM42688_SIGNAL_PATH_RESET_FIFO_FLUSH);
  dev->fifo_flush_us = icm42688_now(dev);
  dev->int_status &= (uint8_t) ~(ICM42688_INT_STATUS_FIFO_FULL | ICM42688_INT_STATUS_FIFO_THS);
  return status;
}

static icm42688_status_t icm42688_check_id(icm42688_t *const dev) {
  uint8_t id = 0u;
  const icm42688_status_t status = icm42688_read_registers(dev, 0u, ICM42688_REG_WHO_AM_I, &id, 1u);
  if (status != ICM42688_OK) return status;
  return id == ICM42688_WHO_AM_I_VALUE ? ICM42688_OK : ICM42688_WRONG_ID;
}

static icm42688_status_t icm42688_reset_and_identify(icm42688_t *const dev) {
  icm42688_status_t status = icm42688_check_id(dev);
  if (status != ICM42688_OK) return status;
  status = icm42688_write_register(dev, 0u, ICM42688_REG_DEVICE_CONFIG,
                                   ICM42688_DEVICE_CONFIG_SOFT_RESET);
  if (status != ICM42688_OK) return status;
  icm42688_wait_us(dev, ICM42688_RESET_WAIT_US);
  dev->bank = 0u; /* the reset selects bank 0 */
  status = icm42688_check_id(dev);
  if (status != ICM42688_OK) return status;
  return icm42688_poll_int_status(dev); /* clears RESET_DONE */
}

icm42688_status_t icm42688_init(icm42688_t *const dev, const bus_t *const bus, uint8_t address) {
  memset(dev, 0, sizeof(*dev));
  dev->bus = bus;
  dev->address = address;
  dev->bank = ICM42688_BANK_UNKNOWN;
  dev->config = icm42688_config_default;
  if (address != ICM42688_ADDRESS_AD0_LOW && address != ICM42688_ADDRESS_AD0_HIGH) {
    dev->last_status = ICM42688_BAD_CONFIG;
    return dev->last_status;
  }
  const icm42688_status_t status = icm42688_reset_and_identify(dev);
  dev->initialised = status == ICM42688_OK;
  dev->int_status = 0u;
  dev->last_status = status;
  return status;
}

static bool icm42688_config_valid(const icm42688_config_t *const config) {
  return icm42688_odr_supported(config->odr_hz) &&
         icm42688_fs_select(config->acc_range_g, 16u) >= 0 &&
         icm42688_fs_select(config->gyro_range_dps, 2000u) >= 0 &&
         config->fifo_watermark_samples >= 1u &&
         config->fifo_watermark_samples <= ICM42688_WATERMARK_MAX_SAMPLES;
}

/* One register write per entry, stopping at the first failure. */
typedef struct {
  uint8_t reg;
  uint8_t value;
} icm42688_write_t;

static icm42688_status_t icm42688_write_all(icm42688_t *const dev,
                                            const icm42688_write_t *const writes, size_t n) {
  for (size_t i = 0; i < n; ++i) {
    const icm42688_status_t status =
        icm42688_write_register(dev, 0u, writes[i].reg, writes[i].value);
    if (status != ICM42688_OK) return status;
  }
  return ICM42688_OK;
}

static icm42688_status_t icm42688_write_signal_path(icm42688_t *const dev,
                                                    const icm42688_config_t *const config) {
  const uint8_t odr = icm42688_odr_find(config->odr_hz)->code;
  const uint8_t acc_fs = (uint8_t)icm42688_fs_select(config->acc_range_g, 16u);
  const uint8_t gyr_fs = (uint8_t)icm42688_fs_select(config->gyro_range_dps, 2000u);
  const bool fast = config->odr_hz >= 4000u;
  const icm42688_write_t writes[] = {
      {ICM42688_REG_INT_SOURCE0, 0u}, /* no edge while the FIFO is reconfigured */
      {ICM42688_REG_FIFO_CONFIG, ICM42688_FIFO_CONFIG_BYPASS},
      {ICM42688_REG_GYRO_CONFIG0, (uint8_t)((gyr_fs << ICM42688_CONFIG0_FS_SHIFT) | odr)},
      {ICM42688_REG_ACCEL_CONFIG0, (uint8_t)((acc_fs << ICM42688_CONFIG0_FS_SHIFT) | odr)},
      {ICM42688_REG_INTF_CONFIG0,
       ICM42688_INTF_CONFIG0_FIFO_COUNT_REC | ICM42688_INTF_CONFIG0_FIFO_COUNT_BIG |
           ICM42688_INTF_CONFIG0_DATA_BIG | ICM42688_INTF_CONFIG0_SPI_DISABLE},
      {ICM42688_REG_FIFO_CONFIG1, ICM42688_FIFO_CONFIG1_TEMP_EN | ICM42688_FIFO_CONFIG1_GYRO_EN |
                                      ICM42688_FIFO_CONFIG1_ACCEL_EN},
      {ICM42688_REG_FIFO_CONFIG2, (uint8_t)(config->fifo_watermark_samples & 0xFFu)},
      {ICM42688_REG_FIFO_CONFIG3, (uint8_t)(config->fifo_watermark_samples >> 8)},
      {ICM42688_REG_INT_CONFIG,
       ICM42688_INT_CONFIG_INT1_PUSH_PULL | ICM42688_INT_CONFIG_INT1_ACTIVE_HIGH},
      /* ASYNC_RESET cleared (the datasheet requires it for INT1); short pulses at 4 kHz+ */
      {ICM42688_REG_INT_CONFIG1,
       fast ? (uint8_t)(ICM42688_INT_CONFIG1_TPULSE_8US | ICM42688_INT_CONFIG1_TDEASSERT_OFF) : 0u},
  };
  return icm42688_write_all(dev, writes, sizeof(writes) / sizeof(writes[0]));
}

static icm42688_status_t icm42688_power_sensors(icm42688_t *const dev) {
  const uint8_t on = ICM42688_PWR_MGMT0_GYRO_LN | ICM42688_PWR_MGMT0_ACCEL_LN;
  uint8_t power = 0u;
  icm42688_status_t status = icm42688_read_registers(dev, 0u, ICM42688_REG_PWR_MGMT0, &power, 1u);
  if (status != ICM42688_OK || power == on) return status;
  status = icm42688_write_register(dev, 0u, ICM42688_REG_PWR_MGMT0, on);
  if (status != ICM42688_OK) return status;
  icm42688_wait_us(dev, ICM42688_POWER_WAIT_US);
  icm42688_wait_us(dev, ICM42688_GYRO_START_US);
  return ICM42688_OK;
}

static void icm42688_set_scales(icm42688_t *const dev) {
  dev->acc_mps2_per_lsb =
      (float)dev->config.acc_range_g * ICM42688_STANDARD_GRAVITY_MPS2 / ICM42688_FULL_SCALE_LSB;
  dev->gyr_rads_per_lsb =
      (float)dev->config.gyro_range_dps * ICM42688_RAD_PER_DEG / ICM42688_FULL_SCALE_LSB;
}

icm42688_status_t icm42688_configure(icm42688_t *const dev, const icm42688_config_t *const config) {
  if (!icm42688_config_valid(config)) return ICM42688_BAD_CONFIG;
  if (!dev->initialised) return ICM42688_NOT_READY;
  dev->configured = false;
  icm42688_status_t status = icm42688_write_signal_path(dev, config);
  if (status == ICM42688_OK) status = icm42688_power_sensors(dev);
  const icm42688_write_t start[] = {
      {ICM42688_REG_FIFO_CONFIG, ICM42688_FIFO_CONFIG_STREAM},
      {ICM42688_REG_INT_SOURCE0, ICM42688_INT_SOURCE0_FIFO_THS_INT1},
  };
  if (status == ICM42688_OK) status = icm42688_write_all(dev, start, 2u);
  if (status == ICM42688_OK) status = icm42688_poll_int_status(dev); /* stale bits */
  if (status == ICM42688_OK) status = icm42688_flush_fifo(dev);
  dev->last_status = status;
  if (status != ICM42688_OK) return status;
  dev->int_status = 0u;
  dev->config = *config;
  icm42688_set_scales(dev);
  dev->configured = true;
  return ICM42688_OK;
}

int16_t icm42688_be16(const uint8_t *const bytes) {
  return (int16_t)(uint16_t)(((uint16_t)bytes[0] << 8) | bytes[1]);
}

static bool icm42688_axis_clipped(int16_t raw) {
  return raw >= ICM42688_CLIP_LSB || raw <= -ICM42688_CLIP_LSB;
}

void icm42688_convert(const icm42688_t *const dev, const uint8_t raw[12], float temp_degc,
                      imu_sample_t *const sample) {
  sample->acc_clipped = false;
  sample->gyr_clipped = false;
  for (size_t axis = 0; axis < 3u; ++axis) {
    const int16_t acc = icm42688_be16(&raw[2u * axis]);
    const int16_t gyr = icm42688_be16(&raw[6u + 2u * axis]);
    sample->acc_mps2[axis] = (float)acc * dev->acc_mps2_per_lsb;
    sample->gyr_rads[axis] = (float)gyr * dev->gyr_rads_per_lsb;
    sample->acc_clipped = sample->acc_clipped || icm42688_axis_clipped(acc);
    sample->gyr_clipped = sample->gyr_clipped || icm42688_axis_clipped(gyr);
  }
  sample->temp_degc = temp_degc;
}
