/* Tests of the sample clock: unit tests on synthetic edges, then end to end with the
 * ICM-42688-P driver and the fake chip (its own oscillator off nominal, the FIFO read
 * late and irregularly, interrupt latency jitter), checking every sample's time against
 * the instant the fake chip took it. */
/* cmocka.h needs the headers before it. */
/* clang-format off */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
/* clang-format on */

#include "fake_icm42688.h"
#include "icm42688.h"
#include "sample_clock.h"

/* ---------------------------------------------------------------------------------- */
/* Unit tests: synthetic edges                                                         */

static sample_clock_t synthetic_clock(uint32_t restart_us) {
  sample_clock_t clock;
  sample_clock_settings_t settings = sample_clock_settings_default;
  settings.settle_interrupts = 4u;
  sample_clock_init(&clock, &settings);
  sample_clock_restart(&clock, 1000u, 10u, restart_us);
  return clock;
}

/* Edges of a chip whose period is `period_us`, each read right after its edge:
 * sample k taken at start + (k + 1) * period. Returns the stamp of the last sample read. */
static void feed_prompt_reads(sample_clock_t *const clock, uint32_t start_us, double period_us,
                              unsigned edges, uint32_t *const last_time_us,
                              uint32_t *const last_index) {
  uint32_t times[10];
  for (unsigned e = 0; e < edges; ++e) {
    const uint32_t index = e * 10u + 9u;
    const uint32_t edge_us = start_us + (uint32_t)llround((index + 1u) * period_us);
    sample_clock_interrupt(clock, edge_us);
    sample_clock_stamp(clock, edge_us + 100u, edge_us + 200u, 10u, times);
    *last_time_us = times[9];
    *last_index = index;
  }
}

static void test_first_edge_belongs_to_the_watermark_sample(void **state) {
  (void)state;
  /* Fixture: restarted at 5000 us, watermark 10, period 1000 us */
  sample_clock_t clock = synthetic_clock(5000u);
  uint32_t times[12];
  /* Test: the edge of sample 9 at 15000 us, then 12 samples read */
  sample_clock_interrupt(&clock, 15000u);
  const sample_clock_status_t status = sample_clock_stamp(&clock, 16500u, 16600u, 12u, times);
  /* Assert: sample 9 at the edge (+0.5 us timer rounding), neighbours one period apart */
  assert_int_equal(status, SAMPLE_CLOCK_SETTLING);
  assert_true(abs((int)(times[9] - 15000u)) <= 1);
  assert_true(abs((int)(times[0] - 6000u)) <= 1);
  assert_true(abs((int)(times[11] - 17000u)) <= 1);
}

static void test_interrupts_before_the_restart_are_discarded(void **state) {
  (void)state;
  /* Fixture */
  sample_clock_t clock = synthetic_clock(100000u);
  uint32_t times[10];
  /* Test: an edge from before the flush, then none */
  sample_clock_interrupt(&clock, 99000u);
  const sample_clock_status_t status = sample_clock_stamp(&clock, 101000u, 101100u, 1u, times);
  /* Assert */
  assert_int_equal(clock.edges_stale, 1u);
  assert_int_equal(status, SAMPLE_CLOCK_NO_LOCK);
}

static void test_fit_measures_a_period_off_nominal(void **state) {
  (void)state;
  /* Fixture: the chip 1.3 % slow */
  sample_clock_t clock = synthetic_clock(0u);
  uint32_t last_time = 0u, last_index = 0u;
  /* Test */
  feed_prompt_reads(&clock, 0u, 1013.0, 40u, &last_time, &last_index);
  /* Assert: the period and the newest stamp */
  assert_float_equal(sample_clock_period_us(&clock), 1013.0f, 0.01f);
  assert_true(abs((int)(last_time - (uint32_t)llround((last_index + 1u) * 1013.0))) <= 1);
}

static void test_stamps_continue_across_the_timer_wrap(void **state) {
  (void)state;
  /* Fixture: restart 50 ms before the 32-bit timer wraps */
  const uint32_t start = UINT32_MAX - 50000u;
  sample_clock_t clock = synthetic_clock(start);
  uint32_t last_time = 0u, last_index = 0u;
  /* Test: 100 ms of edges, across the wrap */
  feed_prompt_reads(&clock, start, 987.0, 10u, &last_time, &last_index);
  /* Assert */
  const uint32_t expected = start + (uint32_t)llround((last_index + 1u) * 987.0);
  assert_true(expected < start); /* wrapped */
  assert_true(abs((int32_t)(last_time - expected)) <= 1);
  assert_float_equal(sample_clock_period_us(&clock), 987.0f, 0.05f);
}

static void test_edge_inside_a_read_takes_the_predicted_index(void **state) {
  (void)state;
  /* Fixture: a settled line at exactly 1000 us */
  sample_clock_t clock = synthetic_clock(0u);
  uint32_t last_time = 0u, last_index = 0u, times[10];
  feed_prompt_reads(&clock, 0u, 1000.0, 20u, &last_time, &last_index);
  const uint32_t used = clock.edges_used;
  /* Test: a read spanning 210.0..212.5 ms; an edge at 211.0 ms (sample 210) inside it */
  sample_clock_stamp(&clock, 210000u, 212500u, 10u, times);
  sample_clock_interrupt(&clock, 211000u);
  /* Assert: used (predicted index 210 lies in the read's range), not dropped */
  assert_int_equal(clock.edges_used, used + 1u);
  assert_int_equal(clock.edges_ambiguous, 0u);
  assert_int_equal(
      clock.edges[(clock.edge_head + clock.edge_count - 1u) % SAMPLE_CLOCK_FIT_SIZE].index, 210u);
}

static void test_an_edge_far_off_the_line_is_rejected(void **state) {
  (void)state;
  /* Fixture */
  sample_clock_t clock = synthetic_clock(0u);
  uint32_t last_time = 0u, last_index = 0u, times[10];
  feed_prompt_reads(&clock, 0u, 1000.0, 20u, &last_time, &last_index);
  const float period = sample_clock_period_us(&clock);
  /* Test: the next edge 300 us late (an interrupt held off) */
  sample_clock_interrupt(&clock, 210000u + 300u);
  sample_clock_stamp(&clock, 210600u, 210700u, 10u, times);
  /* Assert: rejected, the line unchanged */
  assert_int_equal(clock.edges_rejected, 1u);
  assert_float_equal(sample_clock_period_us(&clock), period, 1e-6f);
  assert_true(abs((int)(times[9] - 210000u)) <= 1);
}

/* ---------------------------------------------------------------------------------- */
/* End to end: driver + fake chip + clock                                              */

#define E2E_READ_CAPACITY 32u /* the node's sample buffer */
#define E2E_MAX_ERRORS 400000u
#define E2E_PENDING 64u

typedef struct {
  int64_t edge_ns; /* when INT1 rose (fake's clock) */
  int64_t seen_ns; /* when the handler read the timer: edge + latency jitter */
} e2e_edge_t;

typedef struct {
  fake_icm42688_t fake;
  bus_t bus;
  icm42688_t dev;
  sample_clock_t clock;
  icm42688_config_t config;
  uint64_t rng;
  int64_t read_lateness_max_ns; /* the FIFO is read 0..this after an edge */
  int64_t jitter_max_ns;        /* the handler reads the timer 0..this after the edge */
  e2e_edge_t pending[E2E_PENDING];
  size_t pending_count;
  bool read_scheduled;
  int64_t read_at_ns;
  bool reading_enabled; /* false: the node stops reading (to overflow the FIFO) */
  int64_t last_read_ns; /* the node also polls the FIFO after 50 ms without a read */
  uint32_t overflows;
  uint32_t samples;          /* stamped */
  uint32_t samples_settling; /* stamped while the clock was not settled */
  double max_settling_error_us;
  float errors_us[E2E_MAX_ERRORS]; /* |stamp - true| of settled samples */
  uint32_t error_count;
} e2e_t;

static double e2e_random(e2e_t *const e2e) { /* xorshift64*: uniform in [0, 1) */
  e2e->rng ^= e2e->rng >> 12;
  e2e->rng ^= e2e->rng << 25;
  e2e->rng ^= e2e->rng >> 27;
  return (double)((e2e->rng * 2685821657736338717ull) >> 11) / 9007199254740992.0;
}

static void e2e_on_int1(void *context, int64_t time_ns) {
  e2e_t *const e2e = context;
  assert_true(e2e->pending_count < E2E_PENDING);
  const int64_t jitter_ns = (int64_t)(e2e_random(e2e) * (double)e2e->jitter_max_ns);
  e2e->pending[e2e->pending_count++] = (e2e_edge_t){time_ns, time_ns + jitter_ns};
  if (!e2e->read_scheduled) {
    e2e->read_scheduled = true;
    e2e->read_at_ns = time_ns + (int64_t)(e2e_random(e2e) * (double)e2e->read_lateness_max_ns);
  }
}

static uint32_t e2e_timer_at(const e2e_t *const e2e, int64_t time_ns) {
  return e2e->fake.timer_offset_us + (uint32_t)(uint64_t)(time_ns / 1000);
}

/* The node's interrupt queue: edges whose handler has run by now, in order. */
static void e2e_deliver_edges(e2e_t *const e2e) {
  size_t kept = 0u;
  for (size_t i = 0; i < e2e->pending_count; ++i) {
    if (e2e->pending[i].seen_ns <= e2e->fake.now_ns) {
      sample_clock_interrupt(&e2e->clock, e2e_timer_at(e2e, e2e->pending[i].seen_ns));
    } else {
      e2e->pending[kept++] = e2e->pending[i];
    }
  }
  e2e->pending_count = kept;
}

static void e2e_restart_clock(e2e_t *const e2e) {
  sample_clock_restart(&e2e->clock, icm42688_odr_period_us(e2e->config.odr_hz),
                       e2e->config.fifo_watermark_samples, e2e->dev.fifo_flush_us);
}

/* Compares the stamps of `count` samples with the fake's records of them. */
static void e2e_check(e2e_t *const e2e, const uint32_t *const times, size_t count,
                      sample_clock_status_t status) {
  for (size_t i = 0; i < count; ++i) {
    fake_icm42688_record_t record;
    assert_true(fake_icm42688_take_record(&e2e->fake, &record));
    const double true_us = (double)record.time_ns / 1000.0;
    const uint32_t true_floor = e2e->fake.timer_offset_us + (uint32_t)(uint64_t)floor(true_us);
    const double error_us = (double)(int32_t)(times[i] - true_floor) - (true_us - floor(true_us));
    e2e->samples++;
    if (status != SAMPLE_CLOCK_OK) {
      e2e->samples_settling++;
      if (fabs(error_us) > e2e->max_settling_error_us) e2e->max_settling_error_us = fabs(error_us);
    } else if (e2e->error_count < E2E_MAX_ERRORS) {
      e2e->errors_us[e2e->error_count++] = (float)fabs(error_us);
    }
  }
}

/* One poll of the node: interrupts to the clock, then the FIFO drained and stamped. */
static void e2e_read(e2e_t *const e2e) {
  e2e->read_scheduled = false;
  e2e->last_read_ns = e2e->fake.now_ns;
  e2e_deliver_edges(e2e);
  imu_sample_t samples[E2E_READ_CAPACITY];
  uint32_t times[E2E_READ_CAPACITY];
  size_t count = E2E_READ_CAPACITY;
  while (count == E2E_READ_CAPACITY) {
    bool overflowed = false;
    const uint32_t start = fake_icm42688_timer_us(&e2e->fake);
    assert_int_equal(icm42688_read_fifo(&e2e->dev, samples, E2E_READ_CAPACITY, &count, &overflowed),
                     ICM42688_OK);
    const uint32_t end = fake_icm42688_timer_us(&e2e->fake);
    const sample_clock_status_t status = sample_clock_stamp(&e2e->clock, start, end, count, times);
    e2e_check(e2e, times, count, status);
    if (overflowed) {
      e2e->overflows++;
      e2e_restart_clock(e2e);
    }
  }
}

#define E2E_POLL_TIMEOUT_NS 50000000

static void e2e_run_until(e2e_t *const e2e, int64_t end_ns) {
  while (e2e->fake.now_ns < end_ns) {
    int64_t next_ns = fake_icm42688_next_sample_ns(&e2e->fake);
    if (e2e->read_scheduled && e2e->read_at_ns < next_ns) next_ns = e2e->read_at_ns;
    const int64_t poll_ns = e2e->last_read_ns + E2E_POLL_TIMEOUT_NS;
    if (poll_ns < next_ns) next_ns = poll_ns;
    if (end_ns < next_ns) next_ns = end_ns;
    fake_icm42688_advance_to_ns(&e2e->fake, next_ns);
    const bool due =
        (e2e->read_scheduled && e2e->fake.now_ns >= e2e->read_at_ns) || e2e->fake.now_ns >= poll_ns;
    if (!due) continue;
    if (e2e->reading_enabled) {
      e2e_read(e2e);
    } else {
      e2e->read_scheduled = false;
      e2e->last_read_ns = e2e->fake.now_ns;
    }
  }
}

static void e2e_configure(e2e_t *const e2e, uint16_t odr_hz) {
  e2e->config.odr_hz = odr_hz;
  assert_int_equal(icm42688_configure(&e2e->dev, &e2e->config), ICM42688_OK);
  e2e->read_scheduled = false;
  e2e->last_read_ns = e2e->fake.now_ns;
  e2e_restart_clock(e2e);
}

/* A node at 1 kHz, I2C at 1 MHz (9 us a byte), the chip `ppm` off, timer starting at
 * `timer_offset_us`; the interrupt handler's latency 0..10 us (mean 5 us, known). */
static e2e_t *e2e_create(int32_t ppm, uint32_t timer_offset_us) {
  e2e_t *const e2e = test_calloc(1u, sizeof(e2e_t));
  assert_non_null(e2e);
  fake_icm42688_init(&e2e->fake, ICM42688_ADDRESS_AD0_LOW);
  e2e->fake.clock_error_ppm = ppm;
  e2e->fake.timer_offset_us = timer_offset_us;
  e2e->fake.bus_byte_ns = 9000u;
  fake_icm42688_set_int1(&e2e->fake, e2e_on_int1, e2e);
  e2e->bus = fake_icm42688_bus(&e2e->fake);
  e2e->rng = 0x9E3779B97F4A7C15ull ^ (uint64_t)(int64_t)ppm;
  e2e->read_lateness_max_ns = 30000000;
  e2e->jitter_max_ns = 10000;
  e2e->reading_enabled = true;
  sample_clock_settings_t settings = sample_clock_settings_default;
  settings.interrupt_latency_us = 5.0f; /* the mean of the simulated 0..10 us */
  settings.interrupt_jitter_us = 10.0f;
  sample_clock_init(&e2e->clock, &settings);
  assert_int_equal(icm42688_init(&e2e->dev, &e2e->bus, ICM42688_ADDRESS_AD0_LOW), ICM42688_OK);
  e2e->config = icm42688_config_default;
  e2e_configure(e2e, 1000u);
  return e2e;
}

static int e2e_compare(const void *a, const void *b) {
  const float x = *(const float *)a, y = *(const float *)b;
  return (x > y) - (x < y);
}

/* Max and 99th percentile of the settled errors, printed; returns the max. */
static float e2e_report(e2e_t *const e2e, const char *const name) {
  assert_true(e2e->error_count > 0u);
  qsort(e2e->errors_us, e2e->error_count, sizeof(float), e2e_compare);
  const float max_us = e2e->errors_us[e2e->error_count - 1u];
  const float p99_us = e2e->errors_us[(size_t)((double)(e2e->error_count - 1u) * 0.99)];
  print_message(
      "[ sample clock ] %s: %u samples settled, max %.2f us, p99 %.2f us; "
      "%u settling (max %.1f us); edges used %u (in a read %u), dropped %u, rejected %u\n",
      name, e2e->error_count, (double)max_us, (double)p99_us, e2e->samples_settling,
      e2e->max_settling_error_us, e2e->clock.edges_used, e2e->clock.edges_in_read,
      e2e->clock.edges_ambiguous, e2e->clock.edges_rejected);
  return max_us;
}

static void e2e_expect_within_5us(int32_t ppm, const char *const name) {
  /* Fixture */
  e2e_t *const e2e = e2e_create(ppm, 123456789u);
  /* Test: 60 s */
  e2e_run_until(e2e, 60000000000);
  /* Assert: settled within 1.5 s, then every sample within 5 us */
  const float max_us = e2e_report(e2e, name);
  const double produced = 60000.0 * (1.0 + ppm * 1e-6);
  assert_true(e2e->samples_settling < 1500u);
  assert_true(e2e->error_count > produced - 1500.0);
  assert_true(max_us <= 5.0f);
  assert_int_equal(e2e->overflows, 0u);
  test_free(e2e);
}

static void test_e2e_late_reads_chip_1_3_percent_fast(void **state) {
  (void)state;
  e2e_expect_within_5us(13000, "60 s, chip +1.3 %");
}

static void test_e2e_late_reads_chip_2_percent_slow(void **state) {
  (void)state;
  e2e_expect_within_5us(-20000, "60 s, chip -2 %");
}

static void test_e2e_late_reads_chip_2_percent_fast(void **state) {
  (void)state;
  e2e_expect_within_5us(20000, "60 s, chip +2 %");
}

static void test_e2e_slow_odr_drift(void **state) {
  (void)state;
  /* Fixture: the chip's oscillator drifting 3 ppm/s (warming up), from -1 % */
  e2e_t *const e2e = e2e_create(-10000, 0u);
  /* Test: 60 s, the drift applied every 100 ms */
  for (int64_t t_ns = 0; t_ns < 60000000000; t_ns += 100000000) {
    e2e_run_until(e2e, t_ns);
    e2e->fake.clock_error_ppm = -10000 + (int32_t)(3 * (t_ns / 1000000000));
  }
  /* Assert */
  assert_int_equal(e2e->fake.clock_error_ppm, -10000 + 3 * 59);
  assert_true(e2e_report(e2e, "60 s, chip drifting 3 ppm/s") <= 5.0f);
  assert_true(e2e->error_count > 57000u);
  test_free(e2e);
}

static void test_e2e_timer_wraps(void **state) {
  (void)state;
  /* Fixture: the node timer wraps 5 s into the run */
  e2e_t *const e2e = e2e_create(-7000, UINT32_MAX - 5000000u);
  /* Test */
  e2e_run_until(e2e, 10000000000);
  /* Assert */
  assert_true(fake_icm42688_timer_us(&e2e->fake) < 6000000u); /* wrapped */
  assert_true(e2e_report(e2e, "10 s, timer wraps at 5 s") <= 5.0f);
  assert_true(e2e->error_count > 8000u);
  test_free(e2e);
}

static void test_e2e_overflow_is_reported_and_recovers(void **state) {
  (void)state;
  /* Fixture: running 2 s */
  e2e_t *const e2e = e2e_create(13000, 0u);
  e2e_run_until(e2e, 2000000000);
  const uint32_t settled_before = e2e->error_count;
  /* Test: the node stops reading for 300 ms (the FIFO holds 128 ms), then resumes */
  e2e->reading_enabled = false;
  e2e_run_until(e2e, 2300000000);
  e2e->reading_enabled = true;
  e2e_run_until(e2e, 8000000000);
  /* Assert: one overflow, a restart, settled again and accurate */
  assert_int_equal(e2e->overflows, 1u);
  assert_int_equal(e2e->clock.restarts, 2u); /* configuration, overflow */
  assert_true(e2e->error_count > settled_before + 4000u);
  assert_true(e2e_report(e2e, "overflow at 2.3 s, recovered") <= 5.0f);
  test_free(e2e);
}

static void test_e2e_odr_change(void **state) {
  (void)state;
  /* Fixture: 1 kHz for 2 s */
  e2e_t *const e2e = e2e_create(-13000, 0u);
  e2e_run_until(e2e, 2000000000);
  /* Test: reconfigured to 500 Hz, 8 s more */
  e2e_configure(e2e, 500u);
  const uint32_t settled_before = e2e->error_count;
  e2e_run_until(e2e, 10000000000);
  /* Assert: the new period measured, every settled sample within 5 us */
  assert_float_equal(sample_clock_period_us(&e2e->clock), 2000.0f / 0.987f, 0.05f);
  assert_true(e2e->error_count > settled_before + 3000u);
  assert_true(e2e_report(e2e, "1 kHz -> 500 Hz at 2 s") <= 5.0f);
  test_free(e2e);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_first_edge_belongs_to_the_watermark_sample),
      cmocka_unit_test(test_interrupts_before_the_restart_are_discarded),
      cmocka_unit_test(test_fit_measures_a_period_off_nominal),
      cmocka_unit_test(test_stamps_continue_across_the_timer_wrap),
      cmocka_unit_test(test_edge_inside_a_read_takes_the_predicted_index),
      cmocka_unit_test(test_an_edge_far_off_the_line_is_rejected),
      cmocka_unit_test(test_e2e_late_reads_chip_1_3_percent_fast),
      cmocka_unit_test(test_e2e_late_reads_chip_2_percent_slow),
      cmocka_unit_test(test_e2e_late_reads_chip_2_percent_fast),
      cmocka_unit_test(test_e2e_slow_odr_drift),
      cmocka_unit_test(test_e2e_timer_wraps),
      cmocka_unit_test(test_e2e_overflow_is_reported_and_recovers),
      cmocka_unit_test(test_e2e_odr_change),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
