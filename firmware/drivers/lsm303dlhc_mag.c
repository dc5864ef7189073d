/* The LSM303DLHC's magnetometer (lsm303dlhc_mag.h). */
#include "lsm303dlhc_mag.h"

#include <stddef.h>

#define CRA_ODR_SHIFT 2u
#define CRB_GAIN_SHIFT 5u
#define DATA_BYTES 6u

const lsm303dlhc_mag_settings_t lsm303dlhc_mag_settings_default = {
    .odr = LSM303DLHC_MAG_ODR_220_HZ,
    .range = LSM303DLHC_MAG_RANGE_1_3_GAUSS,
};

/* Sensitivity per range code (datasheet table 3), LSB/gauss; code 0 is undefined. */
static const uint16_t gain_xy_lsb_per_gauss[8] = {0u, 1100u, 855u, 670u, 450u, 400u, 330u, 230u};
static const uint16_t gain_z_lsb_per_gauss[8] = {0u, 980u, 760u, 600u, 400u, 355u, 295u, 205u};

#define UT_PER_GAUSS 100.0f

static bool settings_valid(const lsm303dlhc_mag_settings_t *const settings) {
  return (unsigned)settings->odr <= (unsigned)LSM303DLHC_MAG_ODR_220_HZ &&
         settings->range >= LSM303DLHC_MAG_RANGE_1_3_GAUSS &&
         settings->range <= LSM303DLHC_MAG_RANGE_8_1_GAUSS;
}

float lsm303dlhc_mag_ut_per_count(lsm303dlhc_mag_range_t range, unsigned axis) {
  if (range < LSM303DLHC_MAG_RANGE_1_3_GAUSS || range > LSM303DLHC_MAG_RANGE_8_1_GAUSS) {
    return 0.0f;
  }
  const uint16_t lsb_per_gauss =
      axis == 2u ? gain_z_lsb_per_gauss[range] : gain_xy_lsb_per_gauss[range];
  return UT_PER_GAUSS / (float)lsb_per_gauss;
}

/* Records the outcome of an operation; any failure forces a reconfiguration. */
static lsm303dlhc_mag_status_t finish(lsm303dlhc_mag_t *const mag,
                                      lsm303dlhc_mag_status_t status) {
  mag->last_status = status;
  if (status != LSM303DLHC_MAG_OK && status != LSM303DLHC_MAG_OVERFLOWED) {
    mag->configured = false;
    mag->failures++;
  }
  return status;
}

static lsm303dlhc_mag_status_t from_bus(bus_status_t status) {
  switch (status) {
    case BUS_OK:
      return LSM303DLHC_MAG_OK;
    case BUS_NACK:
      return LSM303DLHC_MAG_NACK;
    default:
      return LSM303DLHC_MAG_BUS_ERROR;
  }
}

static lsm303dlhc_mag_status_t read_registers(const lsm303dlhc_mag_t *const mag, uint8_t reg,
                                              uint8_t *data, size_t length) {
  return from_bus(mag->bus->read(mag->bus->context, mag->address, reg, data, length));
}

static lsm303dlhc_mag_status_t write_register(const lsm303dlhc_mag_t *const mag, uint8_t reg,
                                              uint8_t value) {
  return from_bus(mag->bus->write(mag->bus->context, mag->address, reg, &value, 1u));
}

lsm303dlhc_mag_status_t lsm303dlhc_mag_init(lsm303dlhc_mag_t *const mag,
                                            const bus_t *const bus, uint8_t address,
                                            const lsm303dlhc_mag_settings_t *const settings) {
  mag->bus = bus;
  mag->address = address;
  mag->settings = *settings;
  mag->configured = false;
  mag->failures = 0u;
  mag->last_status = settings_valid(settings) ? LSM303DLHC_MAG_OK : LSM303DLHC_MAG_BAD_SETTING;
  return mag->last_status;
}

lsm303dlhc_mag_status_t lsm303dlhc_mag_probe(lsm303dlhc_mag_t *const mag) {
  uint8_t id[3] = {0u, 0u, 0u};
  lsm303dlhc_mag_status_t status = read_registers(mag, LSM303DLHC_MAG_REG_IRA, id, sizeof id);
  if (status == LSM303DLHC_MAG_OK &&
      (id[0] != LSM303DLHC_MAG_ID_A || id[1] != LSM303DLHC_MAG_ID_B ||
       id[2] != LSM303DLHC_MAG_ID_C)) {
    status = LSM303DLHC_MAG_WRONG_ID;
  }
  return finish(mag, status);
}

lsm303dlhc_mag_status_t lsm303dlhc_mag_configure(lsm303dlhc_mag_t *const mag) {
  if (!settings_valid(&mag->settings)) {
    return finish(mag, LSM303DLHC_MAG_BAD_SETTING);
  }
  lsm303dlhc_mag_status_t status = lsm303dlhc_mag_probe(mag);
  if (status != LSM303DLHC_MAG_OK) {
    return status;
  }
  const uint8_t wanted[3] = {
      (uint8_t)((unsigned)mag->settings.odr << CRA_ODR_SHIFT),
      (uint8_t)((unsigned)mag->settings.range << CRB_GAIN_SHIFT),
      LSM303DLHC_MAG_MR_CONTINUOUS,
  };
  for (uint8_t reg = 0u; reg < 3u && status == LSM303DLHC_MAG_OK; reg++) {
    status = write_register(mag, (uint8_t)(LSM303DLHC_MAG_REG_CRA + reg), wanted[reg]);
  }
  uint8_t actual[3] = {0u, 0u, 0u};
  if (status == LSM303DLHC_MAG_OK) {
    status = read_registers(mag, LSM303DLHC_MAG_REG_CRA, actual, sizeof actual);
  }
  if (status == LSM303DLHC_MAG_OK &&
      (actual[0] != wanted[0] || actual[1] != wanted[1] || (actual[2] & 0x03u) != wanted[2])) {
    status = LSM303DLHC_MAG_CONFIG_LOST;
  }
  mag->configured = status == LSM303DLHC_MAG_OK;
  return finish(mag, status);
}

static int16_t big_endian_12bit(const uint8_t *bytes) {
  return (int16_t)(uint16_t)(((unsigned)bytes[0] << 8) | bytes[1]);
}

lsm303dlhc_mag_status_t lsm303dlhc_mag_read_counts(lsm303dlhc_mag_t *const mag,
                                                   int16_t counts[3]) {
  if (!mag->configured) {
    const lsm303dlhc_mag_status_t status = lsm303dlhc_mag_configure(mag);
    if (status != LSM303DLHC_MAG_OK) {
      return status;
    }
  }
  uint8_t raw[DATA_BYTES];
  const lsm303dlhc_mag_status_t status =
      read_registers(mag, LSM303DLHC_MAG_REG_OUT_X_H, raw, sizeof raw);
  if (status != LSM303DLHC_MAG_OK) {
    return finish(mag, status);
  }
  counts[0] = big_endian_12bit(&raw[0]); /* X */
  counts[1] = big_endian_12bit(&raw[4]); /* Y: last on the chip */
  counts[2] = big_endian_12bit(&raw[2]); /* Z: between X and Y */
  const bool overflow = counts[0] == LSM303DLHC_MAG_OVERFLOW_COUNTS ||
                        counts[1] == LSM303DLHC_MAG_OVERFLOW_COUNTS ||
                        counts[2] == LSM303DLHC_MAG_OVERFLOW_COUNTS;
  return finish(mag, overflow ? LSM303DLHC_MAG_OVERFLOWED : LSM303DLHC_MAG_OK);
}

lsm303dlhc_mag_status_t lsm303dlhc_mag_read_ut(lsm303dlhc_mag_t *const mag, float field_ut[3]) {
  int16_t counts[3];
  const lsm303dlhc_mag_status_t status = lsm303dlhc_mag_read_counts(mag, counts);
  if (status != LSM303DLHC_MAG_OK) {
    return status;
  }
  for (unsigned axis = 0u; axis < 3u; axis++) {
    field_ut[axis] = (float)counts[axis] * lsm303dlhc_mag_ut_per_count(mag->settings.range, axis);
  }
  return status;
}
