/* I2C transfers as a bus_t (g4_i2c.h). Set-up and recovery: g4_i2c_setup.c. */
#include "g4_i2c.h"

#include "g4_i2c_regs.h"
#include "g4_i2c_setup.h"
#include "g4_timer.h"

/* Waits for `flag`; NACK, a bus error or the timeout end the wait first. The time is read
 * before the flags, so a wait that an interrupt stretched past the timeout still sees a
 * flag that rose meanwhile. */
static bus_status_t g4_i2c_wait(const g4_i2c_t *const i2c, uint32_t flag, uint32_t fail_mask) {
  const uint32_t base = i2c->config->base;
  const uint32_t start_us = g4_timer_now_us();
  for (;;) {
    const uint32_t elapsed_us = g4_timer_now_us() - start_us;
    const uint32_t status = I2C_ISR(base);
    if ((status & flag) != 0u) {
      return BUS_OK;
    }
    if ((status & fail_mask & I2C_ISR_NACKF) != 0u) {
      return BUS_NACK;
    }
    if ((status & fail_mask & I2C_ISR_ERRORS) != 0u) {
      return BUS_ERROR;
    }
    if (elapsed_us > i2c->wait_timeout_us) {
      return BUS_TIMEOUT;
    }
  }
}

static bus_status_t g4_i2c_wait_flag(const g4_i2c_t *const i2c, uint32_t flag) {
  return g4_i2c_wait(i2c, flag, I2C_ISR_NACKF | I2C_ISR_ERRORS);
}

/* Programs the next phase of at most 255 bytes out of `remaining`: with a START (and the
 * address) for a new phase, or as the continuation of a reload. Returns its byte count. */
static size_t g4_i2c_phase(uint32_t base, uint8_t device, bool read, size_t remaining,
                           bool start, bool stop_at_end) {
  const size_t count = remaining > I2C_NBYTES_MAX ? I2C_NBYTES_MAX : remaining;
  uint32_t cr2 = ((uint32_t)device << 1) | ((uint32_t)count << I2C_CR2_NBYTES_SHIFT);
  cr2 |= read ? I2C_CR2_RD_WRN : 0u;
  cr2 |= remaining > I2C_NBYTES_MAX ? I2C_CR2_RELOAD : (stop_at_end ? I2C_CR2_AUTOEND : 0u);
  cr2 |= start ? I2C_CR2_START : 0u;
  I2C_CR2(base) = cr2;
  return count;
}

/* Sends the register address and `length` data bytes; ends with a STOP, or (for a read)
 * with the bus held for a repeated START. */
static bus_status_t g4_i2c_send(const g4_i2c_t *const i2c, uint8_t device, uint8_t reg,
                                const uint8_t *data, size_t length, bool stop) {
  const uint32_t base = i2c->config->base;
  const size_t total = 1u + length;
  size_t in_phase = g4_i2c_phase(base, device, false, total, true, stop);
  for (size_t sent = 0u; sent < total;) {
    bus_status_t status = g4_i2c_wait_flag(i2c, I2C_ISR_TXIS);
    if (status != BUS_OK) {
      return status;
    }
    I2C_TXDR(base) = sent == 0u ? reg : data[sent - 1u];
    sent++;
    if (--in_phase == 0u && sent < total) {
      if ((status = g4_i2c_wait_flag(i2c, I2C_ISR_TCR)) != BUS_OK) {
        return status;
      }
      in_phase = g4_i2c_phase(base, device, false, total - sent, false, stop);
    }
  }
  return g4_i2c_wait_flag(i2c, stop ? I2C_ISR_STOPF : I2C_ISR_TC);
}

/* Repeated START, address+R, `length` bytes, NACK and STOP (AUTOEND). */
static bus_status_t g4_i2c_receive(const g4_i2c_t *const i2c, uint8_t device, uint8_t *data,
                                   size_t length) {
  const uint32_t base = i2c->config->base;
  size_t in_phase = g4_i2c_phase(base, device, true, length, true, true);
  for (size_t received = 0u; received < length;) {
    bus_status_t status = g4_i2c_wait_flag(i2c, I2C_ISR_RXNE);
    if (status != BUS_OK) {
      return status;
    }
    data[received++] = (uint8_t)I2C_RXDR(base);
    if (--in_phase == 0u && received < length) {
      if ((status = g4_i2c_wait_flag(i2c, I2C_ISR_TCR)) != BUS_OK) {
        return status;
      }
      in_phase = g4_i2c_phase(base, device, true, length - received, false, true);
    }
  }
  return g4_i2c_wait_flag(i2c, I2C_ISR_STOPF);
}

bus_status_t g4_i2c_read(void *context, uint8_t device, uint8_t reg, uint8_t *data,
                         size_t length) {
  g4_i2c_t *const i2c = context;
  if (data == NULL && length > 0u) {
    return BUS_ERROR;
  }
  bus_status_t status = g4_i2c_begin(i2c);
  if (status == BUS_OK) {
    status = g4_i2c_send(i2c, device, reg, NULL, 0u, length == 0u);
  }
  if (status == BUS_OK && length > 0u) {
    status = g4_i2c_receive(i2c, device, data, length);
  }
  return g4_i2c_end(i2c, status);
}

bus_status_t g4_i2c_write(void *context, uint8_t device, uint8_t reg, const uint8_t *data,
                          size_t length) {
  g4_i2c_t *const i2c = context;
  if (data == NULL && length > 0u) {
    return BUS_ERROR;
  }
  bus_status_t status = g4_i2c_begin(i2c);
  if (status == BUS_OK) {
    status = g4_i2c_send(i2c, device, reg, data, length, true);
  }
  return g4_i2c_end(i2c, status);
}

static void g4_i2c_delay_us(void *context, uint32_t microseconds) {
  (void)context;
  g4_timer_delay_us(microseconds);
}

static uint32_t g4_i2c_now_us(void *context) {
  (void)context;
  return g4_timer_now_us();
}

bus_t g4_i2c_bus(g4_i2c_t *const i2c) {
  return (bus_t){.read = g4_i2c_read,
                 .write = g4_i2c_write,
                 .delay_us = g4_i2c_delay_us,
                 .now_us = g4_i2c_now_us,
                 .context = i2c};
}
