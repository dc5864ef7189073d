/* Tests of the ICM-42688-P driver against the register-level fake chip. */
/* cmocka.h needs the headers before it. */
/* clang-format off */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
/* clang-format on */

#include "fake_icm42688.h"
#include "icm42688.h"
#include "icm42688_regs.h"

#define GRAVITY_MPS2 9.80665
#define RAD_PER_DEG 0.017453292519943295
#define READ_CAPACITY 128u

typedef struct {
  fake_icm42688_t fake;
  bus_t bus;
  icm42688_t dev;
  double amplitude; /* fraction of the full scales the synthetic motion reaches */
  double acc_range_mps2;
  double gyr_range_rads;
  imu_sample_t samples[READ_CAPACITY];
} fixture_t;

/* Synthetic motion: every axis a different sine at `amplitude` of the full scales. */
static void synthetic_source(void *context, uint32_t sequence, int64_t time_ns, float gyr_rads[3],
                             float acc_mps2[3]) {
  const fixture_t *const f = context;
  const double t = (double)time_ns * 1e-9;
  (void)sequence;
  for (unsigned axis = 0; axis < 3u; ++axis) {
    gyr_rads[axis] = (float)(f->amplitude * f->gyr_range_rads * sin(7.0 * t + axis));
    acc_mps2[axis] = (float)(f->amplitude * f->acc_range_mps2 * cos(3.0 * t + 2.0 * axis));
  }
}

static int setup(void **state) {
  fixture_t *const f = test_calloc(1u, sizeof(fixture_t));
  fake_icm42688_init(&f->fake, ICM42688_ADDRESS_AD0_LOW);
  f->fake.clock_error_ppm = 13000;
  f->bus = fake_icm42688_bus(&f->fake);
  f->amplitude = 0.9;
  fake_icm42688_set_source(&f->fake, synthetic_source, f);
  *state = f;
  return 0;
}

static int teardown(void **state) {
  test_free(*state);
  return 0;
}

static icm42688_config_t config_of(uint16_t odr_hz, uint8_t acc_g, uint16_t gyr_dps,
                                   uint16_t watermark) {
  const icm42688_config_t config = {odr_hz, acc_g, gyr_dps, watermark};
  return config;
}

static void start(fixture_t *const f, const icm42688_config_t *const config) {
  f->acc_range_mps2 = config->acc_range_g * GRAVITY_MPS2;
  f->gyr_range_rads = config->gyro_range_dps * RAD_PER_DEG;
  assert_int_equal(icm42688_init(&f->dev, &f->bus, ICM42688_ADDRESS_AD0_LOW), ICM42688_OK);
  assert_int_equal(icm42688_configure(&f->dev, config), ICM42688_OK);
}

/* Reads the FIFO once; checks every sample against the fake's record within 1 LSB. */
static size_t read_and_compare(fixture_t *const f) {
  size_t count = 0u;
  bool overflowed = true;
  assert_int_equal(icm42688_read_fifo(&f->dev, f->samples, READ_CAPACITY, &count, &overflowed),
                   ICM42688_OK);
  assert_false(overflowed);
  for (size_t i = 0; i < count; ++i) {
    fake_icm42688_record_t record;
    assert_true(fake_icm42688_take_record(&f->fake, &record));
    for (unsigned axis = 0; axis < 3u; ++axis) {
      assert_float_equal(f->samples[i].acc_mps2[axis], record.acc_mps2[axis],
                         f->dev.acc_mps2_per_lsb);
      assert_float_equal(f->samples[i].gyr_rads[axis], record.gyr_rads[axis],
                         f->dev.gyr_rads_per_lsb);
    }
    assert_false(f->samples[i].acc_clipped);
    assert_false(f->samples[i].gyr_clipped);
  }
  return count;
}

/* --- identification, reset, bus failures ------------------------------------------ */

static void test_init_resets_and_identifies(void **state) {
  fixture_t *const f = *state;
  /* Test */
  const icm42688_status_t status = icm42688_init(&f->dev, &f->bus, ICM42688_ADDRESS_AD0_LOW);
  /* Assert: reset once, waited for it (no NACK), bank 0 */
  assert_int_equal(status, ICM42688_OK);
  assert_int_equal(f->fake.soft_resets, 1u);
  assert_true(f->dev.initialised);
  assert_int_equal(f->fake.bank, 0u);
  assert_int_equal(f->fake.timing_violations + f->fake.protocol_errors, 0u);
}

static void test_init_refuses_another_chip(void **state) {
  fixture_t *const f = *state;
  /* Fixture: an ICM-42605 (WHO_AM_I 0x42) at the address */
  f->fake.who_am_i = 0x42u;
  /* Test */
  const icm42688_status_t status = icm42688_init(&f->dev, &f->bus, ICM42688_ADDRESS_AD0_LOW);
  /* Assert: refused, and not reset */
  assert_int_equal(status, ICM42688_WRONG_ID);
  assert_false(f->dev.initialised);
  assert_int_equal(f->fake.soft_resets, 0u);
}

static void test_init_reports_nack_at_the_other_address(void **state) {
  fixture_t *const f = *state;
  /* Test: the chip answers at 0x68, the driver asks 0x69 */
  const icm42688_status_t status = icm42688_init(&f->dev, &f->bus, ICM42688_ADDRESS_AD0_HIGH);
  /* Assert */
  assert_int_equal(status, ICM42688_NACK);
  assert_int_equal(icm42688_init(&f->dev, &f->bus, 0x50u), ICM42688_BAD_CONFIG);
}

static void test_nack_while_streaming_is_reported_and_recovered(void **state) {
  fixture_t *const f = *state;
  /* Fixture: streaming */
  const icm42688_config_t config = icm42688_config_default;
  start(f, &config);
  fake_icm42688_advance_us(&f->fake, 20000u);
  size_t count = 0u;
  bool overflowed = false;
  /* Test: the chip drops off the bus, then comes back */
  f->fake.absent = true;
  const icm42688_status_t lost =
      icm42688_read_fifo(&f->dev, f->samples, READ_CAPACITY, &count, &overflowed);
  const icm42688_status_t after =
      icm42688_read_fifo(&f->dev, f->samples, READ_CAPACITY, &count, &overflowed);
  f->fake.absent = false;
  start(f, &config);
  fake_icm42688_advance_us(&f->fake, 20000u);
  /* Assert: NACK, then not ready until re-initialised, then samples again */
  assert_int_equal(lost, ICM42688_NACK);
  assert_int_equal(after, ICM42688_NOT_READY);
  assert_in_range(read_and_compare(f), 20u, 21u);
}

static void test_nack_in_the_middle_of_configure(void **state) {
  fixture_t *const f = *state;
  /* Fixture */
  const icm42688_config_t config = icm42688_config_default;
  assert_int_equal(icm42688_init(&f->dev, &f->bus, ICM42688_ADDRESS_AD0_LOW), ICM42688_OK);
  f->fake.nack_after = 6;
  /* Test */
  const icm42688_status_t status = icm42688_configure(&f->dev, &config);
  /* Assert: reported, unconfigured, and a fresh init + configure works */
  assert_int_equal(status, ICM42688_NACK);
  assert_false(f->dev.configured);
  start(f, &config);
  fake_icm42688_advance_us(&f->fake, 15000u);
  assert_in_range(read_and_compare(f), 15u, 16u);
}

/* --- configuration ------------------------------------------------------------------ */

static void test_configure_refuses_what_the_chip_lacks(void **state) {
  fixture_t *const f = *state;
  /* Fixture */
  assert_int_equal(icm42688_init(&f->dev, &f->bus, ICM42688_ADDRESS_AD0_LOW), ICM42688_OK);
  const uint32_t transfers = f->fake.transfers;
  const icm42688_config_t bad[] = {
      config_of(800u, 16u, 2000u, 10u),
      config_of(1000u, 3u, 2000u, 10u),
      config_of(1000u, 16u, 300u, 10u),
      config_of(1000u, 16u, 2000u, 0u),
      config_of(1000u, 16u, 2000u, ICM42688_WATERMARK_MAX_SAMPLES + 1u),
      config_of(16000u, 16u, 2000u, 10u)};
  /* Test + Assert: each refused without a transfer */
  for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); ++i) {
    assert_int_equal(icm42688_configure(&f->dev, &bad[i]), ICM42688_BAD_CONFIG);
  }
  assert_int_equal(f->fake.transfers, transfers);
}

static void test_every_range_reads_back_what_the_chip_was_fed(void **state) {
  fixture_t *const f = *state;
  static const uint8_t acc_ranges[] = {2u, 4u, 8u, 16u};
  static const uint16_t gyr_ranges[] = {250u, 500u, 1000u, 2000u};
  for (size_t a = 0; a < 4u; ++a) {
    for (size_t g = 0; g < 4u; ++g) {
      /* Fixture */
      const icm42688_config_t config = config_of(200u, acc_ranges[a], gyr_ranges[g], 20u);
      start(f, &config);
      /* Test: 0.5 s of motion up to 90 % of the ranges */
      size_t total = 0u;
      for (int poll = 0; poll < 10; ++poll) {
        fake_icm42688_advance_us(&f->fake, 50000u);
        total += read_and_compare(f);
      }
      /* Assert: (inside read_and_compare) and all samples came (200 Hz, 1.3 % fast) */
      assert_in_range(total, 100u, 102u);
      assert_int_equal(f->fake.timing_violations + f->fake.protocol_errors, 0u);
    }
  }
}

static void test_every_odr_runs_at_its_rate(void **state) {
  fixture_t *const f = *state;
  static const uint16_t rates[] = {25u, 50u, 100u, 200u, 500u, 1000u, 2000u, 4000u, 8000u};
  for (size_t r = 0; r < sizeof(rates) / sizeof(rates[0]); ++r) {
    /* Fixture */
    const icm42688_config_t config = config_of(rates[r], 16u, 2000u, 1u);
    start(f, &config);
    /* Test: at least 100 samples' worth, read every 10 ms (the FIFO holds 16 ms at 8 kHz) */
    const double period_us = icm42688_odr_period_us(rates[r]);
    size_t total = 0u;
    double elapsed_us = 0.0;
    while (elapsed_us < 100.0 * period_us) {
      fake_icm42688_advance_us(&f->fake, 10000u);
      elapsed_us += 10000.0;
      total += read_and_compare(f);
    }
    /* Assert: the chip's rate (1.3 % fast) */
    const double expected = elapsed_us * 1.013 / period_us;
    assert_true(fabs((double)total - expected) <= 1.0);
  }
}

/* --- FIFO, watermark, overflow, clipping -------------------------------------------- */

typedef struct {
  uint32_t edges;
  int64_t last_ns;
} edge_log_t;

static void log_edge(void *context, int64_t time_ns) {
  edge_log_t *const log = context;
  log->edges++;
  log->last_ns = time_ns;
}

static void test_watermark_raises_one_int1_pulse_when_crossed(void **state) {
  fixture_t *const f = *state;
  /* Fixture: 1 kHz, watermark 10 */
  edge_log_t log = {0u, 0};
  fake_icm42688_set_int1(&f->fake, log_edge, &log);
  const icm42688_config_t config = config_of(1000u, 16u, 2000u, 10u);
  start(f, &config);
  const int64_t first_ns = fake_icm42688_next_sample_ns(&f->fake); /* after the flush */
  /* Test: 9 samples, then 1, then 20 ms more unread, then read and 10 ms more */
  fake_icm42688_advance_to_ns(&f->fake, first_ns + 8 * 987167 + 1000);
  const uint32_t before = log.edges;
  fake_icm42688_advance_to_ns(&f->fake, first_ns + 9 * 987167 + 1000);
  const uint32_t at_watermark = log.edges;
  const int64_t edge_ns = log.last_ns;
  fake_icm42688_advance_us(&f->fake, 20000u);
  const uint32_t above = log.edges;
  const size_t read = read_and_compare(f);
  fake_icm42688_advance_us(&f->fake, 10000u);
  /* Assert: one pulse at the 10th sample, none while above, one more after the read */
  assert_int_equal(before, 0u);
  assert_int_equal(at_watermark, 1u);
  assert_true(llabs(edge_ns - (first_ns + 9 * 987167)) < 10);
  assert_int_equal(above, 1u);
  assert_in_range(read, 30u, 31u);
  assert_int_equal(log.edges, 2u);
  assert_int_equal(f->fake.registers[0][ICM42688_REG_INT_CONFIG] & ICM42688_INT_CONFIG_INT1_LATCHED,
                   0u);
}

static void test_overflow_is_reported_and_recovered(void **state) {
  fixture_t *const f = *state;
  /* Fixture: 1 kHz, not read for 200 ms (the FIFO holds 128 ms) */
  const icm42688_config_t config = icm42688_config_default;
  start(f, &config);
  fake_icm42688_advance_us(&f->fake, 200000u);
  size_t count = 99u;
  bool overflowed = false;
  /* Test */
  const icm42688_status_t status =
      icm42688_read_fifo(&f->dev, f->samples, READ_CAPACITY, &count, &overflowed);
  const uint32_t flushed_us = f->dev.fifo_flush_us;
  fake_icm42688_record_t record;
  const bool nothing_read = !fake_icm42688_take_record(&f->fake, &record);
  fake_icm42688_advance_us(&f->fake, 30000u);
  /* Assert: reported with no sample, FIFO flushed then; then samples again */
  assert_int_equal(status, ICM42688_OK);
  assert_true(overflowed);
  assert_int_equal(count, 0u);
  assert_true(nothing_read);
  assert_int_equal(f->dev.fifo_overflows, 1u);
  assert_int_equal(flushed_us, fake_icm42688_timer_us(&f->fake) - 30000u);
  assert_in_range(read_and_compare(f), 30u, 31u);
}

static void test_corrupt_packet_is_reported_and_flushed(void **state) {
  fixture_t *const f = *state;
  /* Fixture: 5 samples, the 3rd one's header damaged */
  const icm42688_config_t config = icm42688_config_default;
  start(f, &config);
  fake_icm42688_advance_us(&f->fake, 5000u);
  f->fake.fifo[(f->fake.fifo_head + 2u) % FAKE_ICM42688_FIFO_PACKETS][0] = 0x10u;
  size_t count = 0u;
  bool overflowed = false;
  /* Test */
  const icm42688_status_t status =
      icm42688_read_fifo(&f->dev, f->samples, READ_CAPACITY, &count, &overflowed);
  /* Assert: the two good ones, then the report; the FIFO empty */
  assert_int_equal(status, ICM42688_FIFO_CORRUPT);
  assert_int_equal(count, 2u);
  assert_true(overflowed);
  assert_int_equal(f->fake.fifo_count, 0u);
}

static void full_scale_source(void *context, uint32_t sequence, int64_t time_ns, float gyr_rads[3],
                              float acc_mps2[3]) {
  (void)context;
  (void)time_ns;
  const bool beyond = sequence % 2u == 1u; /* every other sample beyond the ranges */
  gyr_rads[0] = (float)((beyond ? -2500.0 : 100.0) * RAD_PER_DEG);
  gyr_rads[1] = gyr_rads[2] = 0.0f;
  acc_mps2[0] = acc_mps2[1] = 0.0f;
  acc_mps2[2] = (float)((beyond ? 20.0 : 1.0) * GRAVITY_MPS2);
}

static void test_clipping_is_flagged(void **state) {
  fixture_t *const f = *state;
  /* Fixture: +-16 g, +-2000 deg/s */
  fake_icm42688_set_source(&f->fake, full_scale_source, NULL);
  const icm42688_config_t config = icm42688_config_default;
  start(f, &config);
  fake_icm42688_advance_us(&f->fake, 10000u);
  size_t count = 0u;
  bool overflowed = false;
  /* Test */
  assert_int_equal(icm42688_read_fifo(&f->dev, f->samples, READ_CAPACITY, &count, &overflowed),
                   ICM42688_OK);
  /* Assert: beyond-range samples flagged and at full scale, the others not */
  assert_in_range(count, 10u, 11u);
  for (size_t i = 0; i < count; ++i) {
    fake_icm42688_record_t record;
    assert_true(fake_icm42688_take_record(&f->fake, &record));
    const bool beyond = record.sequence % 2u == 1u;
    assert_int_equal(f->samples[i].acc_clipped, beyond);
    assert_int_equal(f->samples[i].gyr_clipped, beyond);
    if (beyond) {
      assert_float_equal(f->samples[i].acc_mps2[2], (16.0 * GRAVITY_MPS2), 0.01);
      assert_float_equal(f->samples[i].gyr_rads[0], (-2000.0 * RAD_PER_DEG), 0.002);
    }
  }
}

static void test_stuck_chip_repeats_its_sample(void **state) {
  fixture_t *const f = *state;
  /* Fixture */
  const icm42688_config_t config = icm42688_config_default;
  start(f, &config);
  fake_icm42688_advance_us(&f->fake, 3000u);
  size_t count = 0u;
  bool overflowed = false;
  assert_int_equal(icm42688_read_fifo(&f->dev, f->samples, READ_CAPACITY, &count, &overflowed),
                   ICM42688_OK);
  /* Test */
  f->fake.stuck = true;
  fake_icm42688_advance_us(&f->fake, 5000u);
  assert_int_equal(icm42688_read_fifo(&f->dev, f->samples, READ_CAPACITY, &count, &overflowed),
                   ICM42688_OK);
  /* Assert: identical samples (what the node's stuck detector sees) */
  assert_in_range(count, 5u, 6u);
  for (size_t i = 1; i < count; ++i) {
    assert_memory_equal(&f->samples[i], &f->samples[0], sizeof(imu_sample_t));
  }
}

/* --- data-ready, self-test ----------------------------------------------------------- */

static void test_data_ready_then_data_registers(void **state) {
  fixture_t *const f = *state;
  /* Fixture */
  const icm42688_config_t config = config_of(100u, 4u, 500u, 10u);
  start(f, &config);
  bool ready_before = true, ready_after = false, ready_again = true;
  imu_sample_t sample;
  /* Test */
  assert_int_equal(icm42688_data_ready(&f->dev, &ready_before), ICM42688_OK);
  fake_icm42688_advance_us(&f->fake, 10000u);
  assert_int_equal(icm42688_data_ready(&f->dev, &ready_after), ICM42688_OK);
  assert_int_equal(icm42688_read_data(&f->dev, &sample), ICM42688_OK);
  assert_int_equal(icm42688_data_ready(&f->dev, &ready_again), ICM42688_OK);
  /* Assert: ready once; the registers hold the sample just taken */
  assert_false(ready_before);
  assert_true(ready_after);
  assert_false(ready_again);
  for (unsigned axis = 0; axis < 3u; ++axis) {
    assert_float_equal(sample.acc_mps2[axis], f->fake.last_record.acc_mps2[axis],
                       f->dev.acc_mps2_per_lsb);
    assert_float_equal(sample.gyr_rads[axis], f->fake.last_record.gyr_rads[axis],
                       f->dev.gyr_rads_per_lsb);
  }
  assert_float_equal(sample.temp_degc, 25.0f, 0.01f);
}

static void still_source(void *context, uint32_t sequence, int64_t time_ns, float gyr_rads[3],
                         float acc_mps2[3]) {
  (void)context;
  (void)sequence;
  (void)time_ns;
  gyr_rads[0] = 0.01f;
  gyr_rads[1] = -0.02f;
  gyr_rads[2] = 0.005f;
  acc_mps2[0] = 0.3f;
  acc_mps2[1] = -0.2f;
  acc_mps2[2] = 9.8f;
}

static bool run_self_test(fixture_t *const f) {
  fake_icm42688_set_source(&f->fake, still_source, NULL);
  const icm42688_config_t config = icm42688_config_default;
  start(f, &config);
  bool passed = false;
  assert_int_equal(icm42688_self_test(&f->dev, &passed), ICM42688_OK);
  /* the configuration is back and streaming */
  assert_true(f->dev.configured);
  assert_int_equal(f->fake.registers[0][ICM42688_REG_GYRO_CONFIG0], ICM42688_ODR_1KHZ);
  assert_int_equal(f->fake.registers[0][ICM42688_REG_SELF_TEST_CONFIG], 0u);
  assert_int_equal(f->fake.timing_violations + f->fake.protocol_errors, 0u);
  return passed;
}

static void test_self_test_passes_a_good_chip(void **state) {
  fixture_t *const f = *state;
  /* Test + Assert: responses as trimmed (ratio 1), and 1.3x */
  assert_true(run_self_test(f));
  f->fake.st_gyro_ratio = 1.3f;
  f->fake.st_accel_ratio = 0.7f;
  assert_true(run_self_test(f));
}

static void test_self_test_fails_a_weak_gyroscope(void **state) {
  fixture_t *const f = *state;
  /* Fixture: the gyroscope responds at 30 % of its trim */
  f->fake.st_gyro_ratio = 0.3f;
  /* Test + Assert */
  assert_false(run_self_test(f));
}

static void test_self_test_fails_a_strong_accelerometer(void **state) {
  fixture_t *const f = *state;
  /* Fixture */
  f->fake.st_accel_ratio = 1.8f;
  /* Test + Assert */
  assert_false(run_self_test(f));
}

static void test_self_test_without_trim_codes_uses_absolute_limits(void **state) {
  fixture_t *const f = *state;
  /* Fixture: no codes (the factory response then 2620 LSB: 20 deg/s, 0.16 g) */
  static const uint8_t none[3] = {0u, 0u, 0u};
  fake_icm42688_set_trim_codes(&f->fake, none, none);
  /* Test: 20 deg/s is below the 60 deg/s minimum; 3x is enough */
  const bool weak = run_self_test(f);
  f->fake.st_gyro_ratio = 3.5f;
  const bool strong = run_self_test(f);
  /* Assert */
  assert_false(weak);
  assert_true(strong);
}

/* --- real recorded samples ----------------------------------------------------------- */

#define RECORDING_MAX_ROWS 20000u

typedef struct {
  float gyr_rads[RECORDING_MAX_ROWS][3];
  float acc_mps2[RECORDING_MAX_ROWS][3];
  uint32_t rows;
} recording_t;

/* Fusion's handheld recording: time s, gyro deg/s x y z, acc g x y z, mag uT x y z. */
static bool load_recording(const char *const path, recording_t *const recording) {
  FILE *const file = fopen(path, "r");
  if (file == NULL) return false;
  char line[512];
  recording->rows = 0u;
  bool ok = fgets(line, sizeof(line), file) != NULL; /* header */
  while (ok && recording->rows < RECORDING_MAX_ROWS && fgets(line, sizeof(line), file) != NULL) {
    double v[7];
    char *cursor = line;
    for (int i = 0; i < 7; ++i) {
      v[i] = strtod(cursor, &cursor);
      if (*cursor == ',') ++cursor;
    }
    for (unsigned axis = 0; axis < 3u; ++axis) {
      recording->gyr_rads[recording->rows][axis] = (float)(v[1 + axis] * RAD_PER_DEG);
      recording->acc_mps2[recording->rows][axis] = (float)(v[4 + axis] * GRAVITY_MPS2);
    }
    recording->rows++;
  }
  fclose(file);
  return ok && recording->rows > 1000u;
}

static void recording_source(void *context, uint32_t sequence, int64_t time_ns, float gyr_rads[3],
                             float acc_mps2[3]) {
  const recording_t *const recording = context;
  const uint32_t row = sequence % recording->rows;
  (void)time_ns;
  memcpy(gyr_rads, recording->gyr_rads[row], sizeof(recording->gyr_rads[row]));
  memcpy(acc_mps2, recording->acc_mps2[row], sizeof(recording->acc_mps2[row]));
}

static void test_real_recorded_samples_come_back_within_one_lsb(void **state) {
  fixture_t *const f = *state;
  const char *const path = FIRMWARE_SHARED_DIR "/data/imu/handheld/sensor_data.csv";
  FILE *const present = fopen(path, "r");
  if (present == NULL) {
    print_message("skipped: the recording %s is absent (development data)\n", path);
    skip();
  }
  fclose(present);
  recording_t *const recording = test_malloc(sizeof(recording_t));
  assert_true(load_recording(path, recording));
  /* Fixture: the recording (100 Hz, up to 365 deg/s, 1.4 g) at 100 Hz, +-4 g, +-500 deg/s */
  fake_icm42688_set_source(&f->fake, recording_source, recording);
  const icm42688_config_t config = config_of(100u, 4u, 500u, 10u);
  start(f, &config);
  /* Test: the whole recording through the FIFO, read every 100 ms */
  size_t total = 0u;
  while (total < recording->rows) {
    fake_icm42688_advance_us(&f->fake, 100000u);
    total += read_and_compare(f);
  }
  /* Assert (inside read_and_compare): every sample within one LSB of the recording */
  print_message("[ icm42688 ] %zu recorded samples read back within one LSB\n", total);
  test_free(recording);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_init_resets_and_identifies, setup, teardown),
      cmocka_unit_test_setup_teardown(test_init_refuses_another_chip, setup, teardown),
      cmocka_unit_test_setup_teardown(test_init_reports_nack_at_the_other_address, setup, teardown),
      cmocka_unit_test_setup_teardown(test_nack_while_streaming_is_reported_and_recovered, setup,
                                      teardown),
      cmocka_unit_test_setup_teardown(test_nack_in_the_middle_of_configure, setup, teardown),
      cmocka_unit_test_setup_teardown(test_configure_refuses_what_the_chip_lacks, setup, teardown),
      cmocka_unit_test_setup_teardown(test_every_range_reads_back_what_the_chip_was_fed, setup,
                                      teardown),
      cmocka_unit_test_setup_teardown(test_every_odr_runs_at_its_rate, setup, teardown),
      cmocka_unit_test_setup_teardown(test_watermark_raises_one_int1_pulse_when_crossed, setup,
                                      teardown),
      cmocka_unit_test_setup_teardown(test_overflow_is_reported_and_recovered, setup, teardown),
      cmocka_unit_test_setup_teardown(test_corrupt_packet_is_reported_and_flushed, setup, teardown),
      cmocka_unit_test_setup_teardown(test_clipping_is_flagged, setup, teardown),
      cmocka_unit_test_setup_teardown(test_stuck_chip_repeats_its_sample, setup, teardown),
      cmocka_unit_test_setup_teardown(test_data_ready_then_data_registers, setup, teardown),
      cmocka_unit_test_setup_teardown(test_self_test_passes_a_good_chip, setup, teardown),
      cmocka_unit_test_setup_teardown(test_self_test_fails_a_weak_gyroscope, setup, teardown),
      cmocka_unit_test_setup_teardown(test_self_test_fails_a_strong_accelerometer, setup, teardown),
      cmocka_unit_test_setup_teardown(test_self_test_without_trim_codes_uses_absolute_limits, setup,
                                      teardown),
      cmocka_unit_test_setup_teardown(test_real_recorded_samples_come_back_within_one_lsb, setup,
                                      teardown),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
