/* The node end to end with its chips faked at register level (ICM-42688-P with its own
 * oscillator 1.3 % fast, LSM303DLHC magnetometer): it streams the orientation and the
 * acceleration of a held sensor at the output rate, every output stamped with the instant
 * the chip took that sample; and it reports and recovers from what goes wrong on a body:
 * a chip that stops answering, a FIFO read too late, a stuck sensor, a bus that cannot
 * send. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "fake_icm42688.h"
#include "fake_lsm303dlhc_mag.h"
#include "node.h"

#define NODE_ID 7
#define MAX_OUTPUTS 2048

/* The held sensor: a fixed orientation (sensor -> ENU), gravity and the earth's field
 * seen in the sensor frame, with a little noise as a real chip has. */
static const float TRUE_Q[4] = {0.8924f, 0.2391f, -0.1830f, 0.3320f}; /* normalised below */
static const float FIELD_ENU_UT[3] = {0.0f, 20.0f, -42.0f};

typedef struct {
  fake_icm42688_t imu;
  fake_lsm303dlhc_mag_t mag;
  bus_t imu_bus, mag_bus;
  node_t node;
  float q[4];                 /* TRUE_Q normalised */
  uint32_t noise;             /* LCG state */
  node_output_t outputs[MAX_OUTPUTS];
  size_t output_count;
  can_frame_t last_heartbeat;
  size_t frames_sent;
  bool hold_bus;              /* the bus cannot send: frames stay queued */
  size_t stale_samples_sent;  /* sample frames sent more than 30 ms after their sample */
  bool tx_overflow_seen;      /* a heartbeat reported tx_overflow */
  int64_t sample_true_ns[1 << 16]; /* true instant of each sample the node read, in order */
  size_t samples_read;
} fixture_t;

static float noise(fixture_t *const f, float amplitude) {
  f->noise = f->noise * 1664525u + 1013904223u;
  return amplitude * ((float)(f->noise >> 8) / 8388608.0f - 1.0f);
}

/* v in the sensor frame = R(q)^T v_earth. */
static void to_sensor(const float q[4], const float v[3], float out[3]) {
  const float w = q[0], x = q[1], y = q[2], z = q[3];
  const float r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                         {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                         {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
  for (int i = 0; i < 3; ++i) out[i] = r[0][i] * v[0] + r[1][i] * v[1] + r[2][i] * v[2];
}

static void held_sensor(void *context, uint32_t sequence, int64_t time_ns, float gyr_rads[3],
                        float acc_mps2[3]) {
  (void)sequence, (void)time_ns;
  fixture_t *const f = context;
  const float up[3] = {0.0f, 0.0f, 9.80665f};
  to_sensor(f->q, up, acc_mps2);
  for (int i = 0; i < 3; ++i) {
    acc_mps2[i] += noise(f, 0.02f);
    gyr_rads[i] = 0.001f + noise(f, 0.002f); /* a small bias and noise */
  }
}

static void int1(void *context, int64_t time_ns) {
  fixture_t *const f = context;
  node_imu_interrupt(&f->node, (uint32_t)(time_ns / 1000) + f->imu.timer_offset_us);
}

static void record_output(void *context, const node_output_t *output) {
  fixture_t *const f = context;
  if (f->output_count < MAX_OUTPUTS) f->outputs[f->output_count++] = *output;
}

static int setup(void **state) {
  static fixture_t fixture;
  fixture_t *const f = &fixture;
  memset(f, 0, sizeof(*f));
  const float n = sqrtf(TRUE_Q[0] * TRUE_Q[0] + TRUE_Q[1] * TRUE_Q[1] + TRUE_Q[2] * TRUE_Q[2] +
                        TRUE_Q[3] * TRUE_Q[3]);
  for (int i = 0; i < 4; ++i) f->q[i] = TRUE_Q[i] / n;
  fake_icm42688_init(&f->imu, 0x68);
  f->imu.clock_error_ppm = 13000;
  f->imu.timer_offset_us = 0xFFF00000u; /* the node's timer wraps during each test */
  fake_icm42688_set_source(&f->imu, held_sensor, f);
  fake_icm42688_set_int1(&f->imu, int1, f);
  fake_lsm303dlhc_mag_init(&f->mag, 0x1E);
  f->imu_bus = fake_icm42688_bus(&f->imu);
  f->mag_bus = fake_lsm303dlhc_mag_bus(&f->mag);
  node_settings_t settings = node_settings_default;
  settings.node_id = NODE_ID;
  settings.start_running = true;
  settings.on_output = record_output;
  settings.output_context = f;
  node_init(&f->node, &settings, &f->imu_bus, &f->mag_bus);
  *state = f;
  return 0;
}

/* Runs `ms` milliseconds: the chips advance, the field gets its noise, the node polls
 * every millisecond and sends what it queued (unless the bus is held). */
static void run_ms(fixture_t *const f, unsigned ms) {
  for (unsigned i = 0; i < ms; ++i) {
    fake_icm42688_advance_us(&f->imu, 1000u);
    float field[3];
    to_sensor(f->q, FIELD_ENU_UT, field);
    for (int k = 0; k < 3; ++k) field[k] += noise(f, 0.3f);
    fake_lsm303dlhc_mag_set_field_ut(&f->mag, field);
    node_poll(&f->node, fake_icm42688_timer_us(&f->imu));
    fake_icm42688_record_t record;
    while (fake_icm42688_take_record(&f->imu, &record)) {
      f->sample_true_ns[f->samples_read++ % (1 << 16)] = record.time_ns;
    }
    can_frame_t frame;
    const uint32_t now_us = fake_icm42688_timer_us(&f->imu);
    while (!f->hold_bus && node_transmit_next(&f->node, &frame)) {
      f->frames_sent++;
      if (frame.id == 0x700 + NODE_ID) {
        f->last_heartbeat = frame;
        f->tx_overflow_seen |= (frame.data[5] & 0x04) != 0; /* bit 42 */
      }
      if (frame.id == 0x140 + NODE_ID) {
        struct mocap_imu_imu_accel_t accel;
        mocap_imu_imu_accel_unpack(&accel, frame.data, frame.length);
        f->stale_samples_sent += ((now_us - accel.sample_time_us) & 0xFFFFu) > 30000u;
      }
    }
  }
}

static struct mocap_imu_heartbeat_t heartbeat(const fixture_t *const f) {
  struct mocap_imu_heartbeat_t decoded;
  assert_int_equal(f->last_heartbeat.id, 0x700 + NODE_ID);
  mocap_imu_heartbeat_unpack(&decoded, f->last_heartbeat.data, f->last_heartbeat.length);
  return decoded;
}

/* Rotation angle between two unit quaternions, degrees. */
static float angle_deg(const float a[4], const float b[4]) {
  const float dot = fabsf(a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]);
  return 2.0f * acosf(dot > 1.0f ? 1.0f : dot) * 57.29578f;
}

static void test_streams_a_held_sensor_at_the_output_rate(void **state) {
  fixture_t *const f = *state;
  /* Test: 12 s (self-test ~1 s, then the filter's initial averaging and heading) */
  run_ms(f, 12000);
  /* Assert: 100 Hz of a 1.3 % fast 1 kHz chip after the self-test */
  assert_in_range(f->output_count, 1080, 1140);
  const node_output_t *const last = &f->outputs[f->output_count - 1];
  assert_false(last->orientation_invalid);
  assert_true(angle_deg(last->q_wxyz, f->q) < 2.0f);
  float up[3];
  to_sensor(f->q, (const float[3]){0.0f, 0.0f, 9.80665f}, up);
  for (int i = 0; i < 3; ++i) assert_true(fabsf(last->acc_mps2[i] - up[i]) < 0.03f);
  for (size_t k = 1; k < f->output_count; ++k) {
    assert_int_equal(f->outputs[k].seq, (uint8_t)(f->outputs[k - 1].seq + 1));
  }
  assert_int_equal(heartbeat(f).state, 2); /* running */
  assert_int_equal(heartbeat(f).imu_nack + heartbeat(f).fifo_overflow + heartbeat(f).imu_stuck, 0);
}

static void test_every_output_carries_the_instant_the_chip_took_it(void **state) {
  fixture_t *const f = *state;
  run_ms(f, 6000);
  /* Output k ends an interval of 10 samples: it is sample 10 (k + 1) - 1 in reading order. */
  int checked = 0;
  for (size_t k = 200; k < f->output_count; ++k) {
    const size_t sample = 10 * (k + 1) - 1;
    assert_true(sample < f->samples_read);
    const int64_t true_ns = f->sample_true_ns[sample];
    const uint32_t true_us = (uint32_t)(true_ns / 1000) + f->imu.timer_offset_us;
    const int32_t error_us = (int32_t)(f->outputs[k].time_us - true_us);
    assert_in_range(error_us + 5, 0, 10);
    checked++;
  }
  assert_true(checked > 300);
}

static void test_sixty_hertz_from_a_kilohertz_chip(void **state) {
  fixture_t *const f = *state;
  struct {
    uint8_t data[8];
  } set_rate = {{2}}; /* STOP, then SET_RATE 60, then START */
  can_frame_t frame = {.id = 0x600 + NODE_ID, .length = 8};
  run_ms(f, 2000);
  memcpy(frame.data, set_rate.data, 8);
  node_receive(&f->node, &frame, 0);
  frame.data[0] = 3, frame.data[1] = 60, frame.data[2] = 0;
  node_receive(&f->node, &frame, 0);
  frame.data[0] = 1, frame.data[1] = 0;
  node_receive(&f->node, &frame, 0);
  f->output_count = 0;
  run_ms(f, 5000);
  /* 60 Hz of a chip running 1.3 % fast: 5 s of its samples make 304 outputs */
  assert_in_range(f->output_count, 300, 308);
  for (size_t k = 1; k < f->output_count; ++k) {
    const uint32_t gap_us = f->outputs[k].time_us - f->outputs[k - 1].time_us;
    assert_in_range(gap_us, 15700, 16800); /* 16 or 17 samples of 987 us */
  }
}

static void test_a_late_fifo_read_is_reported_and_the_node_recovers(void **state) {
  fixture_t *const f = *state;
  run_ms(f, 3000);
  /* Test: the main loop stalls for 200 ms (the FIFO holds 128 ms) */
  fake_icm42688_advance_us(&f->imu, 200000u);
  run_ms(f, 100);
  /* Assert: reported; samples flow again, their times good once the clock has settled */
  assert_int_equal(heartbeat(f).fifo_overflow, 1);
  f->output_count = 0;
  run_ms(f, 1500);
  assert_in_range(f->output_count, 145, 155);
  run_ms(f, 1100);
  assert_int_equal(heartbeat(f).fifo_overflow, 0);
}

static void test_an_imu_that_stops_answering_is_reported_and_recovers(void **state) {
  fixture_t *const f = *state;
  run_ms(f, 3000);
  f->imu.absent = true;
  run_ms(f, 2500);
  assert_int_equal(heartbeat(f).imu_nack, 1);
  assert_int_equal(heartbeat(f).state, 3); /* fault */
  f->imu.absent = false;
  f->output_count = 0;
  run_ms(f, 3000);
  assert_int_equal(heartbeat(f).state, 2);
  assert_true(f->output_count > 150);
}

static void test_a_stuck_imu_is_reported_and_reset(void **state) {
  fixture_t *const f = *state;
  run_ms(f, 3000);
  const uint32_t resets = f->imu.soft_resets;
  f->imu.stuck = true;
  run_ms(f, 600);
  f->imu.stuck = false;
  run_ms(f, 400);
  assert_int_equal(heartbeat(f).imu_stuck, 1);
  assert_true(f->imu.soft_resets > resets);
  f->output_count = 0;
  run_ms(f, 2000);
  assert_true(f->output_count > 150);
}

static void test_a_missing_magnetometer_leaves_the_heading_to_the_gyroscope(void **state) {
  fixture_t *const f = *state;
  f->mag.present = false;
  run_ms(f, 4000);
  assert_int_equal(heartbeat(f).mag_nack, 1);
  assert_true(f->output_count > 200); /* samples still flow */
  f->mag.present = true;
  run_ms(f, 14000);
  assert_int_equal(heartbeat(f).mag_nack, 0);
  assert_true(angle_deg(f->outputs[f->output_count - 1].q_wxyz, f->q) < 2.0f);
}

static void test_a_bus_that_cannot_send_costs_samples_not_times(void **state) {
  fixture_t *const f = *state;
  run_ms(f, 3000);
  /* Test: the bus sends nothing for 300 ms (the queue holds 14 samples, 140 ms) */
  f->hold_bus = true;
  run_ms(f, 300);
  f->hold_bus = false;
  const size_t outputs = f->output_count;
  run_ms(f, 1100);
  /* Assert: queued samples older than 30 ms were dropped rather than sent with times the
   * hub would restore wrongly; a heartbeat said so; streaming goes on. */
  assert_int_equal(f->stale_samples_sent, 0);
  assert_true(f->tx_overflow_seen);
  assert_in_range(f->output_count - outputs, 105, 115);
}

static void test_a_failed_self_test_is_in_every_heartbeat(void **state) {
  fixture_t *const f = *state;
  /* Fixture: the chip's self-test response is a tenth of its factory value */
  f->imu.st_gyro_ratio = 0.1f;
  /* Test */
  run_ms(f, 3500);
  /* Assert: reported long after start-up, and the node streams anyway */
  assert_int_equal(heartbeat(f).self_test_failed, 1);
  assert_true(f->output_count > 150);
}

static void test_a_passed_self_test_is_not_reported(void **state) {
  fixture_t *const f = *state;
  run_ms(f, 3500);
  assert_int_equal(heartbeat(f).self_test_failed, 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup(test_streams_a_held_sensor_at_the_output_rate, setup),
      cmocka_unit_test_setup(test_every_output_carries_the_instant_the_chip_took_it, setup),
      cmocka_unit_test_setup(test_sixty_hertz_from_a_kilohertz_chip, setup),
      cmocka_unit_test_setup(test_a_late_fifo_read_is_reported_and_the_node_recovers, setup),
      cmocka_unit_test_setup(test_an_imu_that_stops_answering_is_reported_and_recovers, setup),
      cmocka_unit_test_setup(test_a_stuck_imu_is_reported_and_reset, setup),
      cmocka_unit_test_setup(test_a_missing_magnetometer_leaves_the_heading_to_the_gyroscope, setup),
      cmocka_unit_test_setup(test_a_bus_that_cannot_send_costs_samples_not_times, setup),
      cmocka_unit_test_setup(test_a_failed_self_test_is_in_every_heartbeat, setup),
      cmocka_unit_test_setup(test_a_passed_self_test_is_not_reported, setup),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
