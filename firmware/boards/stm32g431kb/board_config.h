/* The production node's wiring (README.md has the same pin map): STM32G431KBU6,
 * UFQFPN32, 16 MHz crystal; ICM-42688-P on I2C1 at 1 MHz (fast-mode plus), the
 * magnetometer on its own I2C2 (a chip stuck on one bus cannot block the other), the
 * IMU's INT1 on TIM2 channel 1, FDCAN1 to a CAN transceiver whose standby pin PB0 holds
 * low. Alternate-function numbers from the datasheet (DS12589) table for the 32-pin part.
 */
#ifndef FIRMWARE_BOARDS_STM32G431KB_BOARD_CONFIG_H
#define FIRMWARE_BOARDS_STM32G431KB_BOARD_CONFIG_H

#include "g4_gpio.h"
#include "g4_i2c.h"

#define BOARD_IMU_I2C_HZ 1000000u /* ICM-42688-P: fast-mode plus */
#define BOARD_MAG_I2C_HZ 400000u  /* LSM303DLHC: its datasheet stops at fast mode */
#define BOARD_I2C_RISE_NS 60u     /* 1 kOhm pull-ups, < 30 pF of short traces and chips */
#define BOARD_I2C_FALL_NS 10u
/* g4_i2c_timing_compute(G4_CLOCK_PCLK1_HZ, rate, rise, fall, digital filter) for each bus,
 * as constants (no 64-bit arithmetic on the node); test_g4_i2c_timing checks they agree.
 * SCL: 977..989 kHz on the IMU's bus, 397..399 kHz on the magnetometer's. */
#define BOARD_IMU_I2C_TIMINGR 0x1090152Eu
#define BOARD_MAG_I2C_TIMINGR 0x10D04181u
#define BOARD_I2C_CR1_FILTER 0x1900u /* digital filter of 9 kernel clocks (53 ns), analog off */
#define BOARD_WATCHDOG_MS 2000u   /* > the slowest loop pass: the IMU self-test, ~0.7 s */
#define BOARD_IRQ_PRIORITY 1u     /* TIM2 and FDCAN share it: neither preempts the other */
/* INT1 is captured by TIM2 in hardware: no handler latency; the spread is the 1 us count
 * plus the chip's own assertion jitter (sample_clock_settings_t). */
#define BOARD_INT1_LATENCY_US 0.0f
#define BOARD_INT1_JITTER_US 2.0f

extern const g4_i2c_config_t board_imu_i2c;
extern const g4_i2c_config_t board_mag_i2c;
extern const g4_gpio_pin_t board_imu_int1; /* PA0, TIM2_CH1 */
extern const g4_gpio_pin_t board_can_rx;   /* PA11, FDCAN1_RX */
extern const g4_gpio_pin_t board_can_tx;   /* PA12, FDCAN1_TX */
extern const g4_gpio_pin_t board_can_standby; /* PB0, transceiver STB: low = normal */

#endif /* FIRMWARE_BOARDS_STM32G431KB_BOARD_CONFIG_H */
