/* GPIO pin set-up: mode, alternate function, output type, pull, speed (RM0440 GPIO). */
#ifndef FIRMWARE_BOARDS_STM32G431KB_G4_GPIO_H
#define FIRMWARE_BOARDS_STM32G431KB_G4_GPIO_H

#include <stdbool.h>
#include <stdint.h>

typedef enum { G4_GPIO_INPUT = 0, G4_GPIO_OUTPUT = 1, G4_GPIO_ALTERNATE = 2 } g4_gpio_mode_t;
typedef enum { G4_GPIO_NO_PULL = 0, G4_GPIO_PULL_UP = 1, G4_GPIO_PULL_DOWN = 2 } g4_gpio_pull_t;

typedef struct {
  uint32_t port;        /* G4_GPIOx_BASE */
  uint8_t pin;          /* 0..15 */
  g4_gpio_mode_t mode;
  uint8_t alternate;    /* AF0..AF15 (datasheet DS12589 table "Alternate functions") */
  bool open_drain;
  g4_gpio_pull_t pull;
  uint8_t speed;        /* 0 low .. 3 very high */
} g4_gpio_pin_t;

void g4_gpio_configure(const g4_gpio_pin_t *const pin);

/* Output level of a pin configured as output (or open drain: true releases the line). */
void g4_gpio_write(const g4_gpio_pin_t *const pin, bool high);

bool g4_gpio_read(const g4_gpio_pin_t *const pin);

#endif /* FIRMWARE_BOARDS_STM32G431KB_G4_GPIO_H */
