/* I2C controller set-up, transfer start and end, bus recovery (g4_i2c_setup.h). */
#include "g4_i2c_setup.h"

#include "g4_i2c_regs.h"
#include "g4_timer.h"

#define I2C_BUS_HZ_PER_US 1000000u
#define I2C_WAIT_BASE_US 100u   /* margin for interrupts served during a wait */
#define I2C_WAIT_BITS 20u       /* a byte and its acknowledge are 9 bits */
#define RECOVERY_PULSES 9u
#define RECOVERY_HALF_PERIOD_US 5u /* 100 kHz: any device follows */
#define PE_OFF_READS 3u            /* RM0440: PE low for at least 3 APB cycles */

static void g4_i2c_enable(const g4_i2c_t *const i2c) {
  const uint32_t base = i2c->config->base;
  const uint32_t filter = i2c->config->cr1_filter; /* set while PE is 0; no interrupts */
  I2C_CR1(base) = filter;
  for (uint32_t i = 0u; i < PE_OFF_READS; i++) {
    (void)I2C_CR1(base);
  }
  I2C_TIMINGR(base) = i2c->config->timingr;
  I2C_CR1(base) = filter | I2C_CR1_PE;
}

void g4_i2c_init(g4_i2c_t *const i2c, const g4_i2c_config_t *const config) {
  *i2c = (g4_i2c_t){.config = config};
  i2c->wait_timeout_us = I2C_WAIT_BASE_US + I2C_WAIT_BITS * I2C_BUS_HZ_PER_US / config->bus_hz;
  G4_RCC_CCIPR &= ~(3u << config->kernel_select_shift); /* PCLK1 */
  G4_RCC_APB1ENR1 |= config->clock_enable;
  (void)G4_RCC_APB1ENR1;
  G4_SYSCFG_CFGR1 |= config->fast_mode_plus;
  g4_i2c_recover(i2c); /* also configures the pins */
  i2c->recoveries = 0u;
  g4_i2c_enable(i2c);
}

static void g4_i2c_pins_to_controller(const g4_i2c_config_t *const config) {
  g4_gpio_configure(&config->scl);
  g4_gpio_configure(&config->sda);
}

void g4_i2c_recover(g4_i2c_t *const i2c) {
  const g4_i2c_config_t *const config = i2c->config;
  g4_gpio_pin_t scl = config->scl;
  g4_gpio_pin_t sda = config->sda;
  scl.mode = G4_GPIO_OUTPUT;
  sda.mode = G4_GPIO_OUTPUT;
  scl.open_drain = sda.open_drain = true;
  g4_gpio_write(&scl, true);
  g4_gpio_write(&sda, true);
  g4_gpio_configure(&scl);
  g4_gpio_configure(&sda);
  g4_timer_delay_us(RECOVERY_HALF_PERIOD_US);
  for (uint32_t pulse = 0u; pulse < RECOVERY_PULSES && !g4_gpio_read(&sda); pulse++) {
    g4_gpio_write(&scl, false);
    g4_timer_delay_us(RECOVERY_HALF_PERIOD_US);
    g4_gpio_write(&scl, true);
    g4_timer_delay_us(RECOVERY_HALF_PERIOD_US);
  }
  /* STOP: SDA rises while SCL is high. */
  g4_gpio_write(&scl, false);
  g4_timer_delay_us(RECOVERY_HALF_PERIOD_US);
  g4_gpio_write(&sda, false);
  g4_timer_delay_us(RECOVERY_HALF_PERIOD_US);
  g4_gpio_write(&scl, true);
  g4_timer_delay_us(RECOVERY_HALF_PERIOD_US);
  g4_gpio_write(&sda, true);
  g4_timer_delay_us(RECOVERY_HALF_PERIOD_US);
  g4_i2c_pins_to_controller(config);
  i2c->recoveries++;
}

bus_status_t g4_i2c_begin(g4_i2c_t *const i2c) {
  const uint32_t base = i2c->config->base;
  const uint32_t start_us = g4_timer_now_us();
  while ((I2C_ISR(base) & I2C_ISR_BUSY) != 0u) {
    if (g4_timer_now_us() - start_us > i2c->wait_timeout_us) {
      return BUS_TIMEOUT; /* g4_i2c_end resets and recovers */
    }
  }
  I2C_ICR(base) = I2C_ICR_ALL;
  return BUS_OK;
}

/* The STOP the controller sends by itself after a NACK; false if it never came. */
static bool g4_i2c_finish_nack(const g4_i2c_t *const i2c) {
  const uint32_t base = i2c->config->base;
  const uint32_t start_us = g4_timer_now_us();
  while ((I2C_ISR(base) & I2C_ISR_STOPF) == 0u) {
    if (g4_timer_now_us() - start_us > i2c->wait_timeout_us) {
      return false;
    }
  }
  return true;
}

bus_status_t g4_i2c_end(g4_i2c_t *const i2c, bus_status_t status) {
  const uint32_t base = i2c->config->base;
  bool reset = status == BUS_TIMEOUT || status == BUS_ERROR;
  if (status == BUS_NACK) {
    i2c->nacks++;
    reset = !g4_i2c_finish_nack(i2c);
  }
  if (reset) {
    i2c->timeouts += status == BUS_TIMEOUT ? 1u : 0u;
    i2c->errors += status == BUS_ERROR ? 1u : 0u;
    I2C_CR1(base) = 0u;
    g4_i2c_recover(i2c);
    g4_i2c_enable(i2c);
  }
  I2C_ICR(base) = I2C_ICR_ALL;
  I2C_ISR(base) = I2C_ISR_TXE; /* flushes a byte left in TXDR */
  I2C_CR2(base) = 0u;
  return status;
}
