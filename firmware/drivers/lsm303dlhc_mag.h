/* The magnetometer of ST's LSM303DLHC (7-bit I2C address 0x1E), behind a bus_t.
 *
 * The chip: identification registers IRA/IRB/IRC = 'H' '4' '3'; CRA sets the output
 * data rate, CRB the gain (full scale), MR the mode (continuous, single, sleep). The
 * data registers run X, Z, Y (not X, Y, Z), high byte first, 12-bit two's complement;
 * an axis whose ADC overflowed reads -4096. Reads auto-increment (Y_L wraps to X_H).
 *
 * Every register is written in its own bus transfer (the chip, and QEMU's model of it,
 * do not advance the pointer on writes). A transfer that fails leaves the driver
 * unconfigured: the next read probes and configures the chip again, so a chip that
 * dropped off the bus (or was power-cycled back to its sleep default) recovers.
 */
#ifndef FIRMWARE_DRIVERS_LSM303DLHC_MAG_H
#define FIRMWARE_DRIVERS_LSM303DLHC_MAG_H

#include <stdbool.h>
#include <stdint.h>

#include "bus.h"

#define LSM303DLHC_MAG_ADDRESS 0x1Eu /* 7-bit I2C address (fixed on the chip) */

#define LSM303DLHC_MAG_REG_CRA 0x00u
#define LSM303DLHC_MAG_REG_CRB 0x01u
#define LSM303DLHC_MAG_REG_MR 0x02u
#define LSM303DLHC_MAG_REG_OUT_X_H 0x03u /* then X_L, Z_H, Z_L, Y_H, Y_L */
#define LSM303DLHC_MAG_REG_SR 0x09u
#define LSM303DLHC_MAG_REG_IRA 0x0Au
#define LSM303DLHC_MAG_REG_IRB 0x0Bu
#define LSM303DLHC_MAG_REG_IRC 0x0Cu

#define LSM303DLHC_MAG_ID_A 0x48u /* 'H' */
#define LSM303DLHC_MAG_ID_B 0x34u /* '4' */
#define LSM303DLHC_MAG_ID_C 0x33u /* '3' */

#define LSM303DLHC_MAG_MR_CONTINUOUS 0x00u
#define LSM303DLHC_MAG_MR_SLEEP 0x03u
#define LSM303DLHC_MAG_OVERFLOW_COUNTS (-4096) /* counts: the ADC overflowed on that axis */

typedef enum {
  LSM303DLHC_MAG_OK = 0,
  LSM303DLHC_MAG_NACK,        /* the chip did not acknowledge (absent, unpowered) */
  LSM303DLHC_MAG_BUS_ERROR,   /* the controller timed out or failed */
  LSM303DLHC_MAG_WRONG_ID,    /* something else answers at the address */
  LSM303DLHC_MAG_CONFIG_LOST, /* a register read back differs from what was written */
  LSM303DLHC_MAG_OVERFLOWED, /* an axis overflowed: no field this time */
  LSM303DLHC_MAG_BAD_SETTING, /* a setting outside the chip's table */
} lsm303dlhc_mag_status_t;

/* Output data rate, CRA bits 4:2. */
typedef enum {
  LSM303DLHC_MAG_ODR_0_75_HZ = 0,
  LSM303DLHC_MAG_ODR_1_5_HZ = 1,
  LSM303DLHC_MAG_ODR_3_HZ = 2,
  LSM303DLHC_MAG_ODR_7_5_HZ = 3,
  LSM303DLHC_MAG_ODR_15_HZ = 4,
  LSM303DLHC_MAG_ODR_30_HZ = 5,
  LSM303DLHC_MAG_ODR_75_HZ = 6,
  LSM303DLHC_MAG_ODR_220_HZ = 7,
} lsm303dlhc_mag_odr_t;

/* Full scale, CRB bits 7:5 (code 0 is not defined by the datasheet). */
typedef enum {
  LSM303DLHC_MAG_RANGE_1_3_GAUSS = 1, /* 1100 LSB/gauss (x, y), 980 (z) */
  LSM303DLHC_MAG_RANGE_1_9_GAUSS = 2, /* 855, 760 */
  LSM303DLHC_MAG_RANGE_2_5_GAUSS = 3, /* 670, 600 */
  LSM303DLHC_MAG_RANGE_4_0_GAUSS = 4, /* 450, 400 */
  LSM303DLHC_MAG_RANGE_4_7_GAUSS = 5, /* 400, 355 */
  LSM303DLHC_MAG_RANGE_5_6_GAUSS = 6, /* 330, 295 */
  LSM303DLHC_MAG_RANGE_8_1_GAUSS = 7, /* 230, 205 */
} lsm303dlhc_mag_range_t;

typedef struct {
  lsm303dlhc_mag_odr_t odr;
  lsm303dlhc_mag_range_t range;
} lsm303dlhc_mag_settings_t;

/* 220 Hz, +-1.3 gauss (+-130 uT: the earth's field is 25-65 uT). */
extern const lsm303dlhc_mag_settings_t lsm303dlhc_mag_settings_default;

typedef struct {
  const bus_t *bus;
  uint8_t address;                    /* 7-bit */
  lsm303dlhc_mag_settings_t settings; /* applied at every (re)configuration */
  bool configured;                    /* false: the next read configures first */
  lsm303dlhc_mag_status_t last_status;
  uint32_t failures;                  /* transfers or checks failed since init */
} lsm303dlhc_mag_t;

/* Binds the driver to a bus and address; talks to nothing yet. */
lsm303dlhc_mag_status_t lsm303dlhc_mag_init(lsm303dlhc_mag_t *const mag,
                                            const bus_t *const bus, uint8_t address,
                                            const lsm303dlhc_mag_settings_t *const settings);

/* Reads IRA/IRB/IRC: OK when the chip is an LSM303DLHC (or its magnetometer twin). */
lsm303dlhc_mag_status_t lsm303dlhc_mag_probe(lsm303dlhc_mag_t *const mag);

/* Probes, writes CRA, CRB and MR (continuous conversion) and reads them back. */
lsm303dlhc_mag_status_t lsm303dlhc_mag_configure(lsm303dlhc_mag_t *const mag);

/* One sample in counts, sensor axes x, y, z (reordered from the chip's X, Z, Y).
 * Configures first when needed. LSM303DLHC_MAG_OVERFLOWED: `counts` holds the
 * sample, the overflowed axes at LSM303DLHC_MAG_OVERFLOW_COUNTS. */
lsm303dlhc_mag_status_t lsm303dlhc_mag_read_counts(lsm303dlhc_mag_t *const mag,
                                                   int16_t counts[3]);

/* One sample in uT, sensor axes x, y, z. `field_ut` is written only on OK. */
lsm303dlhc_mag_status_t lsm303dlhc_mag_read_ut(lsm303dlhc_mag_t *const mag, float field_ut[3]);

/* The resolution of `range` on sensor axis `axis` (0 x, 1 y, 2 z), uT per count; 0 for
 * a range outside the table. */
float lsm303dlhc_mag_ut_per_count(lsm303dlhc_mag_range_t range, unsigned axis);

#endif /* FIRMWARE_DRIVERS_LSM303DLHC_MAG_H */
