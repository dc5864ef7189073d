/* The hardware seam between chip drivers and a board.
 *
 * A driver talks to its chip only through a bus_t: register read and write on a
 * device address, a delay and a microsecond clock. A board fills one in over its I2C
 * (or SPI) controller; a host test fills one in over a register-level fake of the chip.
 * The same driver code therefore builds for the MCU and for the host unchanged.
 */
#ifndef FIRMWARE_DRIVERS_BUS_H
#define FIRMWARE_DRIVERS_BUS_H

#include <stddef.h>
#include <stdint.h>

typedef enum {
  BUS_OK = 0,
  BUS_NACK = -1,     /* the device did not acknowledge (absent, or busy) */
  BUS_TIMEOUT = -2,  /* the controller did not finish in time (bus stuck) */
  BUS_ERROR = -3,    /* arbitration lost, bad argument, controller fault */
} bus_status_t;

typedef struct {
  /* Reads `length` bytes starting at register `reg` of the 7-bit `device` address.
   * Drivers set the chip's auto-increment themselves where the chip needs it. */
  bus_status_t (*read)(void *context, uint8_t device, uint8_t reg, uint8_t *data,
                       size_t length);
  /* Writes `length` bytes starting at register `reg`. */
  bus_status_t (*write)(void *context, uint8_t device, uint8_t reg,
                        const uint8_t *data, size_t length);
  /* Busy-waits at least `microseconds` (start-up times, self-test settling). */
  void (*delay_us)(void *context, uint32_t microseconds);
  /* The board's free-running microsecond timer (wraps at 2^32 us, about 71.6 min). */
  uint32_t (*now_us)(void *context);
  void *context; /* passed back to every callback: the controller, or the fake */
} bus_t;

#endif /* FIRMWARE_DRIVERS_BUS_H */
