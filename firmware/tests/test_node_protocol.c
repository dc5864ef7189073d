/* The node's protocol behaviour with no sensor attached: commands are checked, applied
 * and answered; Sync is answered with its arrival time; malformed frames are refused with
 * a status in the heartbeat; heartbeats report state and status once a second and early
 * when a bit rises; the node never stops answering. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>

#include <cmocka.h>

#include "node.h"
#include "node_internal.h"

#define NODE_ID 5

static bus_status_t absent_read(void *context, uint8_t device, uint8_t reg, uint8_t *data,
                                size_t length) {
  (void)context, (void)device, (void)reg, (void)data, (void)length;
  return BUS_NACK;
}

static bus_status_t absent_write(void *context, uint8_t device, uint8_t reg,
                                 const uint8_t *data, size_t length) {
  (void)context, (void)device, (void)reg, (void)data, (void)length;
  return BUS_NACK;
}

static void no_delay(void *context, uint32_t microseconds) { (void)context, (void)microseconds; }
static uint32_t no_clock(void *context) { (void)context; return 0; }

static const bus_t absent_bus = {absent_read, absent_write, no_delay, no_clock, NULL};

typedef struct {
  node_t node;
  can_frame_t sent[64];
  size_t count;
} fixture_t;

static int setup(void **state) {
  static fixture_t fixture;
  memset(&fixture, 0, sizeof(fixture));
  node_settings_t settings = node_settings_default;
  settings.node_id = NODE_ID;
  node_init(&fixture.node, &settings, &absent_bus, &absent_bus);
  *state = &fixture;
  return 0;
}

/* Runs the node at `now_us` and collects what it sends. */
static void run(fixture_t *const f, uint32_t now_us) {
  node_poll(&f->node, now_us);
  can_frame_t frame;
  while (node_transmit_next(&f->node, &frame)) {
    assert_true(f->count < sizeof(f->sent) / sizeof(f->sent[0]));
    f->sent[f->count++] = frame;
  }
}

/* The last frame sent with base identifier `base`, or NULL. */
static const can_frame_t *last_sent(const fixture_t *const f, uint16_t base) {
  for (size_t i = f->count; i-- > 0;) {
    if (f->sent[i].id == base + NODE_ID) return &f->sent[i];
  }
  return NULL;
}

static struct mocap_imu_command_reply_t command(fixture_t *const f, const uint8_t data[8],
                                                uint8_t length, uint32_t now_us) {
  can_frame_t frame = {.id = CAN_BASE_COMMAND + NODE_ID, .length = length};
  memcpy(frame.data, data, 8);
  node_receive(&f->node, &frame, now_us);
  f->count = 0;
  run(f, now_us);
  const can_frame_t *reply = last_sent(f, CAN_BASE_COMMAND_REPLY);
  assert_non_null(reply);
  struct mocap_imu_command_reply_t decoded;
  assert_int_equal(mocap_imu_command_reply_unpack(&decoded, reply->data, reply->length), 0);
  return decoded;
}

static struct mocap_imu_heartbeat_t heartbeat(const fixture_t *const f) {
  const can_frame_t *frame = last_sent(f, CAN_BASE_HEARTBEAT);
  assert_non_null(frame);
  struct mocap_imu_heartbeat_t decoded;
  assert_int_equal(mocap_imu_heartbeat_unpack(&decoded, frame->data, frame->length), 0);
  return decoded;
}

static void test_an_absent_imu_is_a_fault_reported_every_second(void **state) {
  fixture_t *const f = *state;
  run(f, 1000);
  struct mocap_imu_heartbeat_t hb = heartbeat(f);
  assert_int_equal(hb.state, CAN_STATE_FAULT);
  assert_int_equal(hb.imu_nack, 1);
  assert_int_equal(hb.chip, CAN_CHIP_NONE);
  f->count = 0;
  for (uint32_t t = 2000; t < 3000000; t += 1000) run(f, t);
  size_t heartbeats = 0;
  for (size_t i = 0; i < f->count; ++i) heartbeats += f->sent[i].id == CAN_BASE_HEARTBEAT + NODE_ID;
  assert_in_range(heartbeats, 2, 3); /* once a second: a probe each second re-raises imu_nack */
  assert_int_equal(heartbeat(f).imu_nack, 1);
}

static void test_commands_are_applied_and_answered(void **state) {
  fixture_t *const f = *state;
  run(f, 1000);
  struct mocap_imu_command_reply_t r = command(f, (uint8_t[8]){3, 200, 0}, 8, 2000);
  assert_int_equal(r.command, 3);
  assert_int_equal(r.result, CAN_RESULT_OK);
  assert_int_equal(r.rate_hz, 200);
  r = command(f, (uint8_t[8]){4, 8, 0xE8, 0x03}, 8, 3000); /* 8 g, 1000 deg/s */
  assert_int_equal(r.result, CAN_RESULT_OK);
  assert_int_equal(r.acc_range_g, 8);
  assert_int_equal(r.gyro_range_dps, 1000);
  r = command(f, (uint8_t[8]){5, 0}, 8, 4000);
  assert_int_equal(r.result, CAN_RESULT_OK);
  assert_int_equal(r.mode, NODE_MODE_6D);
  r = command(f, (uint8_t[8]){1}, 8, 5000);
  assert_int_equal(r.running, 1);
  r = command(f, (uint8_t[8]){2}, 8, 6000);
  assert_int_equal(r.running, 0);
}

static void test_bad_commands_change_nothing_and_are_reported(void **state) {
  fixture_t *const f = *state;
  run(f, 1000);
  const struct {
    uint8_t data[8];
    uint8_t length;
    can_result_t result;
  } cases[] = {
      {{3, 0, 0}, 8, CAN_RESULT_BAD_VALUE},          /* rate 0 */
      {{3, 0x91, 0x01}, 8, CAN_RESULT_BAD_VALUE},    /* 401 Hz: over the bus budget */
      {{4, 3, 0xE8, 0x03}, 8, CAN_RESULT_BAD_VALUE}, /* 3 g */
      {{4, 8, 0x2C, 0x01}, 8, CAN_RESULT_BAD_VALUE}, /* 300 deg/s */
      {{5, 2}, 8, CAN_RESULT_BAD_VALUE},             /* mode 2 */
      {{0}, 8, CAN_RESULT_UNKNOWN_COMMAND},
      {{0xFF, 1, 2, 3}, 8, CAN_RESULT_UNKNOWN_COMMAND},
      {{3, 200}, 3, CAN_RESULT_BAD_LENGTH},          /* short frame */
  };
  for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); ++i) {
    const struct mocap_imu_command_reply_t r = command(f, cases[i].data, cases[i].length, 2000 + 1000 * (uint32_t)i);
    assert_int_equal(r.result, cases[i].result);
    assert_int_equal(r.command, cases[i].data[0]);
    assert_int_equal(r.rate_hz, 100); /* unchanged */
    assert_int_equal(r.acc_range_g, 16);
    assert_int_equal(r.gyro_range_dps, 2000);
    assert_int_equal(r.mode, NODE_MODE_9D);
  }
  /* Busy: rate and ranges need the node stopped. */
  command(f, (uint8_t[8]){1}, 8, 20000);
  assert_int_equal(command(f, (uint8_t[8]){3, 50}, 8, 21000).result, CAN_RESULT_BUSY);
  assert_int_equal(command(f, (uint8_t[8]){4, 4, 0xF4, 0x01}, 8, 22000).result, CAN_RESULT_BUSY);
  f->count = 0;
  run(f, 1200000);
  const struct mocap_imu_heartbeat_t hb = heartbeat(f);
  assert_int_equal(hb.command_refused, 1);
  assert_int_equal(hb.frame_malformed, 1);
  assert_int_equal(hb.error_count, 10);
}

static void test_sync_is_answered_with_its_arrival_time(void **state) {
  fixture_t *const f = *state;
  run(f, 1000);
  const can_frame_t sync = {.id = CAN_ID_SYNC, .length = 1, .data = {42}};
  node_receive(&f->node, &sync, 0xFFFFFF00u); /* just before the timer wraps */
  f->count = 0;
  run(f, 0xFFFFFF10u);
  const can_frame_t *report = last_sent(f, CAN_BASE_SYNC_REPORT);
  assert_non_null(report);
  struct mocap_imu_sync_report_t decoded;
  assert_int_equal(mocap_imu_sync_report_unpack(&decoded, report->data, report->length), 0);
  assert_int_equal(decoded.sync_seq, 42);
  assert_int_equal(decoded.rx_time_us, 0xFFFFFF00u);
  run(f, 0xFFFFFF10u + 1100000u); /* across the wrap: the next heartbeat says synced */
  assert_int_equal(heartbeat(f).synced, 1);
  run(f, 0xFFFFFF10u + 3200000u); /* no Sync for 3 s */
  assert_int_equal(heartbeat(f).synced, 0);
}

static void test_frames_for_others_are_ignored_and_malformed_sync_counted(void **state) {
  fixture_t *const f = *state;
  run(f, 1000);
  const can_frame_t other = {.id = CAN_BASE_COMMAND + NODE_ID + 1, .length = 8, .data = {1}};
  const can_frame_t sample = {.id = CAN_BASE_IMU_QUAT + 9, .length = 8};
  const can_frame_t bad_sync = {.id = CAN_ID_SYNC, .length = 0};
  node_receive(&f->node, &other, 2000);
  node_receive(&f->node, &sample, 2000);
  f->count = 0;
  run(f, 2000);
  assert_null(last_sent(f, CAN_BASE_COMMAND_REPLY));
  node_receive(&f->node, &bad_sync, 3000);
  run(f, 3000);
  assert_null(last_sent(f, CAN_BASE_SYNC_REPORT));
  run(f, 1100000);
  assert_int_equal(heartbeat(f).frame_malformed, 1);
  assert_int_equal(heartbeat(f).error_count, 1);
}

static void test_a_flood_of_frames_is_counted_not_fatal(void **state) {
  fixture_t *const f = *state;
  run(f, 1000);
  const can_frame_t start = {.id = CAN_BASE_COMMAND + NODE_ID, .length = 8, .data = {1}};
  for (int i = 0; i < 1000; ++i) node_receive(&f->node, &start, 2000);
  assert_true(f->node.rx_queue.dropped > 0);
  f->count = 0;
  run(f, 2000);
  assert_non_null(last_sent(f, CAN_BASE_COMMAND_REPLY)); /* the ones that fit were answered */
  /* The transmit queue never overflows into lost control frames: later commands answer. */
  assert_int_equal(command(f, (uint8_t[8]){2}, 8, 3000).result, CAN_RESULT_OK);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup(test_an_absent_imu_is_a_fault_reported_every_second, setup),
      cmocka_unit_test_setup(test_commands_are_applied_and_answered, setup),
      cmocka_unit_test_setup(test_bad_commands_change_nothing_and_are_reported, setup),
      cmocka_unit_test_setup(test_sync_is_answered_with_its_arrival_time, setup),
      cmocka_unit_test_setup(test_frames_for_others_are_ignored_and_malformed_sync_counted, setup),
      cmocka_unit_test_setup(test_a_flood_of_frames_is_counted_not_fatal, setup),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
