/* Pins and buses of the production node (board_config.h). */
#include "board_config.h"

#include "g4_regs.h"

#define AF1_TIM2 1u
#define AF4_I2C 4u
#define AF9_FDCAN 9u
#define SPEED_LOW 0u
#define SPEED_MEDIUM 1u
#define SPEED_HIGH 2u

#define I2C_PIN(port_base, number) \
  {.port = (port_base), .pin = (number), .mode = G4_GPIO_ALTERNATE, .alternate = AF4_I2C, \
   .open_drain = true, .pull = G4_GPIO_NO_PULL, .speed = SPEED_MEDIUM}

const g4_i2c_config_t board_imu_i2c = {
    .base = G4_I2C1_BASE,
    .clock_enable = G4_RCC_APB1ENR1_I2C1,
    .kernel_select_shift = 12u,     /* RCC_CCIPR I2C1SEL */
    .fast_mode_plus = 1u << 20,     /* SYSCFG_CFGR1 I2C1_FMP */
    .bus_hz = BOARD_IMU_I2C_HZ,
    .timingr = BOARD_IMU_I2C_TIMINGR,
    .cr1_filter = BOARD_I2C_CR1_FILTER,
    .scl = I2C_PIN(G4_GPIOA_BASE, 15u), /* PA15 I2C1_SCL */
    .sda = I2C_PIN(G4_GPIOB_BASE, 7u),  /* PB7 I2C1_SDA */
};

const g4_i2c_config_t board_mag_i2c = {
    .base = G4_I2C2_BASE,
    .clock_enable = G4_RCC_APB1ENR1_I2C2,
    .kernel_select_shift = 14u,     /* RCC_CCIPR I2C2SEL */
    .fast_mode_plus = 0u,
    .bus_hz = BOARD_MAG_I2C_HZ,
    .timingr = BOARD_MAG_I2C_TIMINGR,
    .cr1_filter = BOARD_I2C_CR1_FILTER,
    .scl = I2C_PIN(G4_GPIOA_BASE, 9u),  /* PA9 I2C2_SCL */
    .sda = I2C_PIN(G4_GPIOA_BASE, 8u),  /* PA8 I2C2_SDA */
};

const g4_gpio_pin_t board_imu_int1 = {.port = G4_GPIOA_BASE, .pin = 0u, .mode = G4_GPIO_ALTERNATE,
                                      .alternate = AF1_TIM2, .pull = G4_GPIO_PULL_DOWN};
const g4_gpio_pin_t board_can_rx = {.port = G4_GPIOA_BASE, .pin = 11u, .mode = G4_GPIO_ALTERNATE,
                                    .alternate = AF9_FDCAN, .pull = G4_GPIO_PULL_UP};
const g4_gpio_pin_t board_can_tx = {.port = G4_GPIOA_BASE, .pin = 12u, .mode = G4_GPIO_ALTERNATE,
                                    .alternate = AF9_FDCAN, .speed = SPEED_HIGH};
const g4_gpio_pin_t board_can_standby = {.port = G4_GPIOB_BASE, .pin = 0u, .mode = G4_GPIO_OUTPUT,
                                         .speed = SPEED_LOW};
