/* Helpers shared by the ICM-42688-P driver's files (not for the application). */
#ifndef FIRMWARE_DRIVERS_ICM42688_INTERNAL_H
#define FIRMWARE_DRIVERS_ICM42688_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "icm42688.h"

#define ICM42688_BANK_UNKNOWN 0xFFu

/* Reads `length` registers from `reg` of `bank` (selects the bank when needed). A
 * failed transfer marks the driver uninitialised and returns NACK or BUS_ERROR. */
icm42688_status_t icm42688_read_registers(icm42688_t *const dev, uint8_t bank, uint8_t reg,
                                          uint8_t *const data, size_t length);

/* Writes one register of `bank`. Failures as icm42688_read_registers. */
icm42688_status_t icm42688_write_register(icm42688_t *const dev, uint8_t bank, uint8_t reg,
                                          uint8_t value);

/* Reads INT_STATUS (which clears it on the chip) into dev->int_status. */
icm42688_status_t icm42688_poll_int_status(icm42688_t *const dev);

/* Empties the FIFO and records the time in dev->fifo_flush_us. */
icm42688_status_t icm42688_flush_fifo(icm42688_t *const dev);

/* Big-endian accel x y z, gyro x y z (12 bytes) and a temperature in deg C to SI units,
 * with the clipped flags. */
void icm42688_convert(const icm42688_t *const dev, const uint8_t raw[12], float temp_degc,
                      imu_sample_t *const sample);

/* Waits up to 1 s for data-ready, then reads the data registers as raw counts
 * (accel x y z, gyro x y z). */
icm42688_status_t icm42688_read_raw_when_ready(icm42688_t *const dev, int16_t raw[6]);

/* Busy-waits through the bus (nothing when the bus has no delay). */
void icm42688_wait_us(const icm42688_t *const dev, uint32_t microseconds);

/* A big-endian int16 from two bytes. */
int16_t icm42688_be16(const uint8_t *const bytes);

#endif /* FIRMWARE_DRIVERS_ICM42688_INTERNAL_H */
