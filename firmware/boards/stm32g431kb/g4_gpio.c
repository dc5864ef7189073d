/* GPIO pin set-up (g4_gpio.h). */
#include "g4_gpio.h"

#include "g4_regs.h"

#define GPIO_MODER(port) G4_REG((port) + 0x00u)
#define GPIO_OTYPER(port) G4_REG((port) + 0x04u)
#define GPIO_OSPEEDR(port) G4_REG((port) + 0x08u)
#define GPIO_PUPDR(port) G4_REG((port) + 0x0Cu)
#define GPIO_IDR(port) G4_REG((port) + 0x10u)
#define GPIO_BSRR(port) G4_REG((port) + 0x18u)
#define GPIO_AFR(port, index) G4_REG((port) + 0x20u + 4u * (index))

/* Writes a field of `width` bits for pin `pin` (fields are packed per pin). */
static void g4_gpio_field(volatile uint32_t *const reg, uint32_t pin, uint32_t width,
                          uint32_t value) {
  const uint32_t shift = pin * width;
  const uint32_t mask = ((1u << width) - 1u) << shift;
  *reg = (*reg & ~mask) | ((value << shift) & mask);
}

void g4_gpio_configure(const g4_gpio_pin_t *const pin) {
  const uint32_t port = pin->port;
  g4_gpio_field(&GPIO_AFR(port, pin->pin / 8u), pin->pin % 8u, 4u, pin->alternate);
  g4_gpio_field(&GPIO_OTYPER(port), pin->pin, 1u, pin->open_drain ? 1u : 0u);
  g4_gpio_field(&GPIO_OSPEEDR(port), pin->pin, 2u, pin->speed);
  g4_gpio_field(&GPIO_PUPDR(port), pin->pin, 2u, (uint32_t)pin->pull);
  g4_gpio_field(&GPIO_MODER(port), pin->pin, 2u, (uint32_t)pin->mode); /* last: no glitch */
}

void g4_gpio_write(const g4_gpio_pin_t *const pin, bool high) {
  GPIO_BSRR(pin->port) = high ? (1u << pin->pin) : (1u << (pin->pin + 16u));
}

bool g4_gpio_read(const g4_gpio_pin_t *const pin) {
  return (GPIO_IDR(pin->port) & (1u << pin->pin)) != 0u;
}
