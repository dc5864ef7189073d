/* Shared between the fake ICM-42688-P's register side and its sensor side. */
#ifndef FIRMWARE_TESTS_SUPPORT_FAKE_ICM42688_INTERNAL_H
#define FIRMWARE_TESTS_SUPPORT_FAKE_ICM42688_INTERNAL_H

#include <stdbool.h>
#include <stdint.h>

#include "fake_icm42688.h"

#define FAKE_ICM42688_NEVER INT64_MAX
#define FAKE_ICM42688_GYRO_START_NS 30000000 /* gyroscope invalid after power-on */
#define FAKE_ICM42688_RESET_NS 1000000       /* soft reset: the chip NACKs meanwhile */
#define FAKE_ICM42688_POWER_WAIT_NS 200000   /* writes lost after a PWR_MGMT0 change */
#define FAKE_ICM42688_DATA_BYTES 14u         /* TEMP_DATA1 .. GYRO_DATA_Z0 */

/* The register at `reg` of bank 0. */
#define FAKE_ICM42688_B0(fake, reg) ((fake)->registers[0][(reg)])

/* True when PWR_MGMT0 `power` has a sensor running (gyro low-noise, accel LP or LN). */
bool fake_icm42688_sensors_on(uint8_t power);

/* (Re)starts the ODR ticks from now at the current ODR, or stops them when off. */
void fake_icm42688_schedule(fake_icm42688_t *const fake);

/* Empties the FIFO and its lost-packet count. */
void fake_icm42688_fifo_flush(fake_icm42688_t *const fake);

/* The next FIFO byte (0xFF when empty); a packet read to its end leaves the FIFO. */
uint8_t fake_icm42688_fifo_pop_byte(fake_icm42688_t *const fake);

/* The FIFO fill level in the unit of FIFO_COUNT (packets or bytes). */
uint16_t fake_icm42688_fifo_level(const fake_icm42688_t *const fake);

/* TEMP_DATA, ACCEL_DATA and GYRO_DATA as the registers read them now. */
void fake_icm42688_data_bytes(const fake_icm42688_t *const fake,
                              uint8_t bytes[FAKE_ICM42688_DATA_BYTES]);

/* `value` in the chip's sensor-data byte order (SENSOR_DATA_ENDIAN). */
void fake_icm42688_put16(const fake_icm42688_t *const fake, uint8_t *const bytes, uint16_t value);

#endif /* FIRMWARE_TESTS_SUPPORT_FAKE_ICM42688_INTERNAL_H */
