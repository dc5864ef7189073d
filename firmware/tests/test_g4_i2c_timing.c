/* The production board's I2C timing on the host (boards/stm32g431kb/g4_i2c_timing.c):
 * every computed TIMINGR is checked against the I2C specification's limits, recomputed
 * here from the register fields with RM0440's formulas, and the constants the board runs
 * with (board_config.h) are proved equal to the computation. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "../boards/stm32g431kb/board_config.h"
#include "../boards/stm32g431kb/g4_clock.h"
#include "../boards/stm32g431kb/g4_i2c_timing.c"

/* UM10204 limits, ns: rate, tLOW, tHIGH, tSU;DAT, tVD;DAT. */
typedef struct {
  uint32_t hz;
  double low, high, setup, valid;
} spec_t;

static const spec_t specs[] = {{100000u, 4700.0, 4000.0, 250.0, 3450.0},
                               {400000u, 1300.0, 600.0, 100.0, 900.0},
                               {1000000u, 500.0, 260.0, 50.0, 450.0}};

/* Recomputes the bus timing from the register fields and checks it against `spec`. */
static void assert_meets_spec(const spec_t *const spec, uint32_t kernel_hz, double rise,
                              double fall, g4_i2c_filter_t filter, const g4_i2c_timing_t *const t) {
  const double clock = 1e9 / kernel_hz;
  const uint32_t r = t->timingr;
  const double tick = clock * (double)((r >> 28) + 1u);
  const double scldel = (double)((r >> 20) & 0xFu), sdadel = (double)((r >> 16) & 0xFu);
  const double sclh = (double)((r >> 8) & 0xFFu), scll = (double)(r & 0xFFu);
  const double dnf = (double)((t->cr1_filter >> 8) & 0xFu);
  const bool analog = (t->cr1_filter & (1u << 12)) == 0u;
  assert_true(analog == (filter == G4_I2C_FILTER_ANALOG));
  assert_true(analog || dnf * clock >= 50.0); /* the filter suppresses 50 ns spikes */
  const double filter_min = analog ? 50.0 : 0.0, filter_max = analog ? 260.0 : 0.0;
  const double sync1 = fall + filter_min + (dnf + 2.0) * clock;
  const double sync2 = rise + filter_min + (dnf + 2.0) * clock;
  assert_true(sync1 + (scll + 1.0) * tick >= spec->low);
  assert_true(sync2 + (sclh + 1.0) * tick >= spec->high);
  assert_true(sync1 + sync2 + (scll + sclh + 2.0) * tick >= 1e9 / spec->hz - 1e-6);
  assert_true(sdadel * tick >= fall - filter_min - (dnf + 3.0) * clock - 1e-6);
  assert_true(sdadel * tick + rise + filter_max + (dnf + 4.0) * clock <= spec->valid);
  assert_true((scldel + 1.0) * tick >= rise + spec->setup);
}

static void test_every_mode_meets_the_specification(void **state) {
  (void)state;
  /* Fixture: the board's clock and others, each mode, both filters. */
  static const uint32_t clocks[] = {170000000u, 48000000u, 16000000u};
  for (size_t c = 0; c < sizeof clocks / sizeof clocks[0]; c++) {
    for (size_t m = 0; m < sizeof specs / sizeof specs[0]; m++) {
      for (int filter = G4_I2C_FILTER_ANALOG; filter <= G4_I2C_FILTER_DIGITAL; filter++) {
        g4_i2c_timing_t timing;
        /* Test */
        const bool ok = g4_i2c_timing_compute(clocks[c], specs[m].hz, 60u, 10u,
                                              (g4_i2c_filter_t)filter, &timing);
        /* Assert: a slow kernel clock may refuse fast-mode plus; what it returns is valid. */
        if (ok) {
          assert_meets_spec(&specs[m], clocks[c], 60.0, 10.0, (g4_i2c_filter_t)filter, &timing);
          assert_true(timing.fastest_hz <= specs[m].hz);
        } else {
          assert_int_equal(specs[m].hz, 1000000u);
        }
      }
    }
  }
}

static void test_digital_filter_gives_a_known_rate(void **state) {
  (void)state;
  /* Fixture: the board's IMU bus. */
  g4_i2c_timing_t digital, analog;
  /* Test */
  assert_true(g4_i2c_timing_compute(170000000u, 1000000u, 60u, 10u, G4_I2C_FILTER_DIGITAL, &digital));
  assert_true(g4_i2c_timing_compute(170000000u, 1000000u, 60u, 10u, G4_I2C_FILTER_ANALOG, &analog));
  /* Assert: within 3 % below 1 MHz with the digital filter; the analog one's delay spread
   * (50..260 ns an edge) leaves a much wider range. */
  assert_in_range(digital.slowest_hz, 970000u, 1000000u);
  assert_in_range(digital.fastest_hz, digital.slowest_hz, 1000000u);
  assert_true(analog.slowest_hz < 800000u);
}

static void test_board_constants_are_the_computed_ones(void **state) {
  (void)state;
  /* Fixture */
  g4_i2c_timing_t imu, mag;
  /* Test */
  assert_true(g4_i2c_timing_compute(G4_CLOCK_PCLK1_HZ, BOARD_IMU_I2C_HZ, BOARD_I2C_RISE_NS,
                                    BOARD_I2C_FALL_NS, G4_I2C_FILTER_DIGITAL, &imu));
  assert_true(g4_i2c_timing_compute(G4_CLOCK_PCLK1_HZ, BOARD_MAG_I2C_HZ, BOARD_I2C_RISE_NS,
                                    BOARD_I2C_FALL_NS, G4_I2C_FILTER_DIGITAL, &mag));
  /* Assert */
  assert_int_equal(imu.timingr, BOARD_IMU_I2C_TIMINGR);
  assert_int_equal(mag.timingr, BOARD_MAG_I2C_TIMINGR);
  assert_int_equal(imu.cr1_filter, BOARD_I2C_CR1_FILTER);
  assert_int_equal(mag.cr1_filter, BOARD_I2C_CR1_FILTER);
}

static void test_refuses_what_cannot_be_met(void **state) {
  (void)state;
  /* Fixture */
  g4_i2c_timing_t timing;
  /* Test and Assert: above fast-mode plus; a rise time over the mode's limit (120 ns in
   * fast-mode plus); a kernel clock too slow for 1 MHz; no clock. */
  assert_false(g4_i2c_timing_compute(170000000u, 1000001u, 60u, 10u, G4_I2C_FILTER_DIGITAL, &timing));
  assert_false(g4_i2c_timing_compute(170000000u, 1000000u, 121u, 10u, G4_I2C_FILTER_DIGITAL, &timing));
  assert_false(g4_i2c_timing_compute(2000000u, 1000000u, 60u, 10u, G4_I2C_FILTER_DIGITAL, &timing));
  assert_false(g4_i2c_timing_compute(0u, 100000u, 60u, 10u, G4_I2C_FILTER_ANALOG, &timing));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_every_mode_meets_the_specification),
      cmocka_unit_test(test_digital_filter_gives_a_known_rate),
      cmocka_unit_test(test_board_constants_are_the_computed_ones),
      cmocka_unit_test(test_refuses_what_cannot_be_met),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
