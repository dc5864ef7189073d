/* The LM3S6965's I2C0 master as a bus_t (board.h), polled.
 *
 * A register read is two transfers: the register pointer written (START, RUN, STOP),
 * then a read (START, RUN ... STOP). QEMU's stellaris-i2c model gives the device no
 * repeated-start event, so a chip latching its data at the start of a read (the
 * LSM303DLHC) would not latch on a write-then-read without the STOP in between.
 * An unanswered address: ADRACK on silicon; QEMU's model reports it as ARBLST (it
 * cannot start the transfer), which a single-master bus cannot otherwise produce. */
#include <stdint.h>

#include "board.h"
#include "lm3s6965.h"

#define SCL_HZ 400000u
#define BUSY_SPINS 100000u /* polls of MCS before BUS_TIMEOUT (~10 ms at 50 MHz) */

static bus_status_t wait_done(void) {
  uint32_t spins = 0u;
  while ((I2C0_MCS & I2C_MCS_BUSY) != 0u) {
    if (++spins >= BUSY_SPINS) {
      return BUS_TIMEOUT;
    }
  }
  const uint32_t status = I2C0_MCS;
  if ((status & I2C_MCS_ERROR) == 0u) {
    return BUS_OK;
  }
  if ((status & I2C_MCS_ARBLST) == 0u) {
    I2C0_MCS = I2C_MCS_STOP; /* the master still holds the bus after a NACK */
  }
  return (status & (I2C_MCS_ADRACK | I2C_MCS_DATACK | I2C_MCS_ARBLST)) != 0u ? BUS_NACK
                                                                             : BUS_ERROR;
}

/* One transfer to `device`: `first` (the register), then `data`; STOP at the end. */
static bus_status_t write_transfer(uint8_t device, uint8_t first, const uint8_t *data,
                                   size_t length) {
  I2C0_MSA = (uint32_t)device << 1;
  I2C0_MDR = first;
  I2C0_MCS = I2C_MCS_START | I2C_MCS_RUN | (length == 0u ? I2C_MCS_STOP : 0u);
  bus_status_t status = wait_done();
  for (size_t i = 0u; i < length && status == BUS_OK; i++) {
    I2C0_MDR = data[i];
    I2C0_MCS = I2C_MCS_RUN | (i + 1u == length ? I2C_MCS_STOP : 0u);
    status = wait_done();
  }
  return status;
}

static bus_status_t read_transfer(uint8_t device, uint8_t *data, size_t length) {
  I2C0_MSA = ((uint32_t)device << 1) | 1u;
  bus_status_t status = BUS_OK;
  for (size_t i = 0u; i < length && status == BUS_OK; i++) {
    const bool last = i + 1u == length;
    I2C0_MCS = (i == 0u ? I2C_MCS_START : 0u) | I2C_MCS_RUN |
               (last ? I2C_MCS_STOP : I2C_MCS_ACK); /* the last byte is not acknowledged */
    status = wait_done();
    data[i] = (uint8_t)I2C0_MDR;
  }
  return status;
}

static bus_status_t i2c_read(void *context, uint8_t device, uint8_t reg, uint8_t *data,
                             size_t length) {
  (void)context;
  if (length == 0u || device > 0x7Fu) {
    return BUS_ERROR;
  }
  const bus_status_t status = write_transfer(device, reg, 0, 0u);
  return status == BUS_OK ? read_transfer(device, data, length) : status;
}

static bus_status_t i2c_write(void *context, uint8_t device, uint8_t reg, const uint8_t *data,
                              size_t length) {
  (void)context;
  if (device > 0x7Fu) {
    return BUS_ERROR;
  }
  return write_transfer(device, reg, data, length);
}

static void i2c_delay_us(void *context, uint32_t microseconds) {
  (void)context;
  board_delay_us(microseconds);
}

static uint32_t i2c_now_us(void *context) {
  (void)context;
  return board_now_us();
}

void board_i2c_init(bus_t *const bus) {
  SYSCTL_RCGC1 |= SYSCTL_RCGC1_I2C0;
  SYSCTL_RCGC2 |= SYSCTL_RCGC2_GPIOB;
  GPIO_AFSEL(GPIO_PORTB) |= 0x0Cu; /* PB2 I2C0SCL, PB3 I2C0SDA */
  GPIO_ODR(GPIO_PORTB) |= 0x08u;   /* SDA open drain */
  GPIO_DEN(GPIO_PORTB) |= 0x0Cu;
  I2C0_MCR = I2C_MCR_MFE;
  /* SCL period = 2 * (1 + TPR) * 10 system clocks. */
  I2C0_MTPR = BOARD_CPU_HZ / (2u * 10u * SCL_HZ) - 1u;
  *bus = (bus_t){.read = i2c_read,
                 .write = i2c_write,
                 .delay_us = i2c_delay_us,
                 .now_us = i2c_now_us,
                 .context = 0};
}
