/* A register-level fake of the LSM303DLHC's magnetometer behind a bus_t, for host tests
 * of the driver (freestanding C11: no libc).
 *
 * It answers like the chip: identification registers, CRA/CRB/MR, data registers in the
 * order X, Z, Y, high byte first, read pointer auto-incrementing (Y_L wraps to X_H,
 * IRC to CRA). The data registers follow the field only in continuous mode (MR = 0) and
 * latch at the start of each read transfer. A field beyond the range reads -4096.
 * Failures on demand: absent (every transfer NACKs), writes ignored, power cycle.
 */
#ifndef FIRMWARE_TESTS_SUPPORT_FAKE_LSM303DLHC_MAG_H
#define FIRMWARE_TESTS_SUPPORT_FAKE_LSM303DLHC_MAG_H

#include <stdbool.h>
#include <stdint.h>

#include "bus.h"

#define FAKE_LSM303DLHC_MAG_REGISTERS 0x0Du /* CRA .. IRC */

typedef struct {
  uint8_t address;                                 /* 7-bit */
  uint8_t registers[FAKE_LSM303DLHC_MAG_REGISTERS]; /* as the chip holds them */
  float field_ut[3];       /* the field the chip sees, sensor axes x y z, uT */
  int16_t field_counts[3]; /* or the counts it reads, whatever the gain */
  bool field_in_counts;    /* true: field_counts (set_counts), false: field_ut */
  uint8_t pointer;         /* register address pointer */
  bool present;            /* false: every transfer NACKs */
  bool ignore_writes;      /* true: writes are acknowledged but not applied */
  uint32_t read_transfers;
  uint32_t write_transfers;
  uint32_t protocol_errors; /* multi-byte writes, writes to read-only registers */
  uint32_t time_us;         /* the fake's clock: advanced by delay_us */
} fake_lsm303dlhc_mag_t;

/* A chip at `address`, just powered on (sleep mode, +-1.3 gauss, 15 Hz). */
void fake_lsm303dlhc_mag_init(fake_lsm303dlhc_mag_t *const fake, uint8_t address);

/* Registers back to their power-on values (a brown-out); the field is kept. */
void fake_lsm303dlhc_mag_power_cycle(fake_lsm303dlhc_mag_t *const fake);

/* The counts the chip reads from now on, whatever its gain, sensor axes x, y, z. */
void fake_lsm303dlhc_mag_set_counts(fake_lsm303dlhc_mag_t *const fake, int16_t x, int16_t y,
                                    int16_t z);

/* The field in uT, converted at the gain in CRB when read (rounded; out of range reads
 * -4096 on that axis, as the chip's overflow). */
void fake_lsm303dlhc_mag_set_field_ut(fake_lsm303dlhc_mag_t *const fake,
                                      const float field_ut[3]);

/* A bus_t whose transfers go to `fake`. */
bus_t fake_lsm303dlhc_mag_bus(fake_lsm303dlhc_mag_t *const fake);

#endif /* FIRMWARE_TESTS_SUPPORT_FAKE_LSM303DLHC_MAG_H */
