/* Set-up, start and end of transfers, and bus recovery of the I2C controllers, for
 * g4_i2c.c (the public interface is g4_i2c.h). */
#ifndef FIRMWARE_BOARDS_STM32G431KB_G4_I2C_SETUP_H
#define FIRMWARE_BOARDS_STM32G431KB_G4_I2C_SETUP_H

#include "g4_i2c.h"

/* Before a transfer: waits (bounded) for an idle bus and clears stale flags. */
bus_status_t g4_i2c_begin(g4_i2c_t *const i2c);

/* After a transfer: on success clears the STOP; on NACK lets the controller's STOP
 * finish; on a timeout or an error resets the controller and recovers the bus. Counts
 * failures and returns `status`. */
bus_status_t g4_i2c_end(g4_i2c_t *const i2c, bus_status_t status);

/* Frees a bus that a device holds (SDA low): up to nine SCL pulses, then a STOP, by hand
 * on the pins, which are given back to the controller after. */
void g4_i2c_recover(g4_i2c_t *const i2c);

#endif /* FIRMWARE_BOARDS_STM32G431KB_G4_I2C_SETUP_H */
