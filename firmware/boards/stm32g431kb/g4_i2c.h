/* A bus_t over one of the G4's I2C controllers (RM0440 "I2C"), polled, as master.
 *
 * read = START, address+W, register, repeated START, address+R, bytes (NACK on the last),
 * STOP; write = START, address+W, register, bytes, STOP. Transfers longer than 255 bytes
 * (a FIFO burst) continue through the controller's reload mode. Every wait is bounded:
 * a device that does not answer gives BUS_NACK (the controller sends the STOP), a bus
 * that does not move gives BUS_TIMEOUT, and a bus error or lost arbitration BUS_ERROR;
 * after a timeout or an error the controller is reset and the bus recovered (nine SCL
 * pulses and a STOP, for a device left holding SDA low), so the next transfer starts
 * clean. Nothing here hangs.
 */
#ifndef FIRMWARE_BOARDS_STM32G431KB_G4_I2C_H
#define FIRMWARE_BOARDS_STM32G431KB_G4_I2C_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "bus.h"
#include "g4_gpio.h"

typedef struct {
  uint32_t base;            /* G4_I2C1_BASE or G4_I2C2_BASE */
  uint32_t clock_enable;    /* its bit in RCC_APB1ENR1 */
  uint32_t kernel_select_shift; /* its I2CxSEL field in RCC_CCIPR (PCLK1 = 0) */
  uint32_t fast_mode_plus;  /* its I2Cx_FMP bit in SYSCFG_CFGR1 (20 mA drive), 0: none */
  uint32_t bus_hz;          /* SCL rate */
  uint32_t timingr;         /* TIMINGR for that rate (g4_i2c_timing; host-tested) */
  uint32_t cr1_filter;      /* CR1's input filter bits (ANFOFF, DNF) that timing assumes */
  g4_gpio_pin_t scl;        /* pins in their I2C alternate function, open drain */
  g4_gpio_pin_t sda;
} g4_i2c_config_t;

typedef struct {
  const g4_i2c_config_t *config;
  uint32_t wait_timeout_us;  /* longest wait for one byte or condition */
  uint32_t nacks;            /* counters, for a debugger */
  uint32_t timeouts;
  uint32_t errors;
  uint32_t recoveries;
} g4_i2c_t;

/* Clocks (kernel clock PCLK1), pins, timing, and a bus recovery. */
void g4_i2c_init(g4_i2c_t *const i2c, const g4_i2c_config_t *const config);

/* The bus_t of the controller: `i2c` is its context. */
bus_t g4_i2c_bus(g4_i2c_t *const i2c);

bus_status_t g4_i2c_read(void *context, uint8_t device, uint8_t reg, uint8_t *data,
                         size_t length);
bus_status_t g4_i2c_write(void *context, uint8_t device, uint8_t reg, const uint8_t *data,
                          size_t length);

#endif /* FIRMWARE_BOARDS_STM32G431KB_G4_I2C_H */
