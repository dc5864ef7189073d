/* Clocks of the production node: SYSCLK = HCLK = PCLK1 = PCLK2 = 170 MHz (the G431's
 * maximum) from the PLL, fed by the 16 MHz crystal (HSE) or, when the crystal does not
 * start, by the internal 16 MHz RC (HSI16): PLL M = 4 (4 MHz in), N = 85 (340 MHz VCO),
 * R = 2. Both sources are 16 MHz, so every derived clock is the same either way; only the
 * accuracy differs (crystal +-50 ppm; HSI16 about +-1 %, which is outside what CAN at
 * 1 Mbit/s tolerates across nodes: see README.md).
 *
 * RM0440 requires, above 150 MHz, the regulator's range 1 boost mode and 4 flash wait
 * states, and when switching to a clock above 80 MHz, HCLK divided by 2 for at least
 * 1 us; g4_clock_init does it in the manual's order. With the crystal, the clock
 * security system is on: a crystal failure raises the NMI, whose handler resets.
 */
#ifndef FIRMWARE_BOARDS_STM32G431KB_G4_CLOCK_H
#define FIRMWARE_BOARDS_STM32G431KB_G4_CLOCK_H

#include <stdbool.h>
#include <stdint.h>

#define G4_CLOCK_SOURCE_HZ 16000000u /* HSE crystal and HSI16 alike */
#define G4_CLOCK_PLL_M 4u
#define G4_CLOCK_PLL_N 85u
#define G4_CLOCK_PLL_R 2u
#define G4_CLOCK_SYSCLK_HZ (G4_CLOCK_SOURCE_HZ / G4_CLOCK_PLL_M * G4_CLOCK_PLL_N / G4_CLOCK_PLL_R)
#define G4_CLOCK_PCLK1_HZ G4_CLOCK_SYSCLK_HZ /* APB1 undivided: TIM2, I2C and FDCAN kernel */
#define G4_CLOCK_FLASH_WAIT_STATES 4u        /* RM0440: <= 170 MHz in range 1 boost */

_Static_assert(G4_CLOCK_SYSCLK_HZ == 170000000u, "the PLL must give 170 MHz");

typedef enum {
  G4_CLOCK_CRYSTAL = 0,   /* PLL from the HSE crystal */
  G4_CLOCK_INTERNAL = 1,  /* the crystal did not start: PLL from HSI16 */
  G4_CLOCK_FAILED = 2,    /* the PLL did not lock: still on HSI16 at 16 MHz */
} g4_clock_source_t;

/* From the reset state (HSI16) to 170 MHz. */
g4_clock_source_t g4_clock_init(void);

#endif /* FIRMWARE_BOARDS_STM32G431KB_G4_CLOCK_H */
