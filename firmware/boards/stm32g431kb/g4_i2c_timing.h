/* The G4 I2C controller's TIMINGR value (and input filter) for a bus rate, computed from
 * the kernel clock and the board's rise and fall times against the I2C specification's
 * limits (NXP UM10204: standard, fast and fast-mode plus) with RM0440's formulas. No
 * hardware: the host tests check it, and the board uses its results as constants that
 * a test proves equal to it (board_config.h).
 *
 * RM0440: tPRESC = (PRESC + 1) tI2CCLK; tLOW = tSYNC1 + (SCLL + 1) tPRESC and
 * tHIGH = tSYNC2 + (SCLH + 1) tPRESC, where tSYNC is the edge (fall, rise) plus the input
 * filter's delay plus 2..3 kernel clocks; data hold SDADEL tPRESC; data set-up
 * (SCLDEL + 1) tPRESC. The filter that suppresses the specification's 50 ns spikes is
 * either the analog one (delay 50..260 ns, so the rate varies by a third at 1 MHz) or the
 * digital one (DNF kernel clocks: a delay known to one clock, so the rate is too). The
 * fields are chosen so that even the shortest delays never make SCL faster than asked.
 */
#ifndef FIRMWARE_BOARDS_STM32G431KB_G4_I2C_TIMING_H
#define FIRMWARE_BOARDS_STM32G431KB_G4_I2C_TIMING_H

#include <stdbool.h>
#include <stdint.h>

#define G4_I2C_ANALOG_FILTER_MIN_NS 50u
#define G4_I2C_ANALOG_FILTER_MAX_NS 260u
#define G4_I2C_SPIKE_NS 50u          /* tSP: spikes the filter must suppress */
#define G4_I2C_DIGITAL_FILTER_MAX 15u /* DNF */
#define G4_I2C_CR1_ANFOFF (1u << 12)
#define G4_I2C_CR1_DNF_SHIFT 8u

typedef enum { G4_I2C_FILTER_ANALOG = 0, G4_I2C_FILTER_DIGITAL = 1 } g4_i2c_filter_t;

typedef struct {
  uint8_t presc;   /* kernel clocks per timing tick, minus one: 0..15 */
  uint8_t scldel;  /* data set-up ticks minus one: 0..15 */
  uint8_t sdadel;  /* data hold ticks: 0..15 */
  uint8_t sclh;    /* SCL high ticks minus one: 0..255 */
  uint8_t scll;    /* SCL low ticks minus one: 0..255 */
  uint8_t dnf;     /* digital filter, kernel clocks (0: analog filter) */
  uint32_t timingr;       /* I2C_TIMINGR */
  uint32_t cr1_filter;    /* I2C_CR1 bits ANFOFF and DNF */
  uint32_t fastest_hz;    /* SCL rate with the shortest delays (never above the request) */
  uint32_t slowest_hz;    /* SCL rate with the longest delays */
  uint32_t low_min_ns;    /* shortest SCL low time */
  uint32_t high_min_ns;   /* shortest SCL high time */
} g4_i2c_timing_t;

/* The timing for `bus_hz` (up to 100 kHz standard, 400 kHz fast, 1 MHz fast-mode plus)
 * with kernel clock `kernel_hz`, the board's SCL/SDA rise and fall times in ns (within
 * the mode's limits) and the filter. False when the mode's limits cannot be met. */
bool g4_i2c_timing_compute(uint32_t kernel_hz, uint32_t bus_hz, uint32_t rise_ns,
                           uint32_t fall_ns, g4_i2c_filter_t filter,
                           g4_i2c_timing_t *const timing);

#endif /* FIRMWARE_BOARDS_STM32G431KB_G4_I2C_TIMING_H */
