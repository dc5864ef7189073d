/* The node's side of the CAN protocol's golden vectors (tests/golden/can_frames.txt): what
 * the node sends packs to exactly the listed bytes, what it receives unpacks to exactly the
 * listed values. The hub's side (cantools) passes the same file: tests/test_can_golden.py. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "can_protocol.h"

#define GOLDEN_MAX_FIELDS 24

typedef struct {
  char message[32];
  unsigned node_id;
  can_frame_t frame;
  char names[GOLDEN_MAX_FIELDS][32];
  double values[GOLDEN_MAX_FIELDS];
  int fields;
} golden_line_t;

/* Parses one vector line; false for comments and blank lines. */
static bool golden_parse(char *line, golden_line_t *const g) {
  if (line[0] == '#' || line[0] == '\n') return false;
  char data[64];
  unsigned identifier = 0;
  int used = 0;
  memset(g, 0, sizeof(*g));
  assert_int_equal(sscanf(line, "%31s %u %x %63s%n", g->message, &g->node_id, &identifier, data, &used), 4);
  g->frame.id = (uint16_t)identifier;
  g->frame.length = (uint8_t)(strlen(data) / 2);
  for (size_t i = 0; i < g->frame.length; ++i) {
    unsigned byte = 0;
    assert_int_equal(sscanf(data + 2 * i, "%2x", &byte), 1);
    g->frame.data[i] = (uint8_t)byte;
  }
  for (char *field = strtok(line + used, " \n"); field; field = strtok(NULL, " \n")) {
    char *equals = strchr(field, '=');
    assert_non_null(equals);
    assert_true(g->fields < GOLDEN_MAX_FIELDS);
    *equals = '\0';
    snprintf(g->names[g->fields], sizeof(g->names[0]), "%s", field);
    g->values[g->fields++] = strtod(equals + 1, NULL);
  }
  return true;
}

static double golden_value(const golden_line_t *const g, const char *name) {
  for (int i = 0; i < g->fields; ++i) {
    if (strcmp(g->names[i], name) == 0) return g->values[i];
  }
  fail_msg("%s has no field %s", g->message, name);
  return 0.0;
}

static void assert_frame_equal(const can_frame_t *const got, const can_frame_t *const want) {
  assert_int_equal(got->id, want->id);
  assert_int_equal(got->length, want->length);
  assert_memory_equal(got->data, want->data, want->length);
}

static void check_sample(const golden_line_t *const quat, const golden_line_t *const accel) {
  node_output_t out = {
      .q_wxyz = {(float)golden_value(quat, "q_w"), (float)golden_value(quat, "q_x"),
                 (float)golden_value(quat, "q_y"), (float)golden_value(quat, "q_z")},
      .acc_mps2 = {(float)golden_value(accel, "a_x"), (float)golden_value(accel, "a_y"),
                   (float)golden_value(accel, "a_z")},
      .time_us = 0xABCD0000u | (uint32_t)golden_value(accel, "sample_time_us"),
      .seq = (uint8_t)golden_value(quat, "seq"),
      .orientation_invalid = golden_value(accel, "orientation_invalid") != 0.0,
      .acc_clipped = golden_value(accel, "acc_clipped") != 0.0,
      .mag_disturbed = golden_value(accel, "mag_disturbed") != 0.0,
  };
  can_frame_t quat_frame, accel_frame;
  can_protocol_pack_sample((uint8_t)quat->node_id, &out, &quat_frame, &accel_frame);
  assert_frame_equal(&quat_frame, &quat->frame);
  assert_frame_equal(&accel_frame, &accel->frame);
}

static void check_heartbeat(const golden_line_t *const g) {
  static const char *const flags[] = {"imu_nack", "mag_nack", "fifo_overflow", "imu_stuck",
                                      "mag_stuck", "command_refused", "frame_malformed",
                                      "self_test_failed", "acc_clipped", "mag_disturbed",
                                      "tx_overflow"};
  can_heartbeat_t heartbeat = {
      .state = (can_state_t)golden_value(g, "state"),
      .mode = (node_mode_t)golden_value(g, "mode"),
      .synced = golden_value(g, "synced") != 0.0,
      .chip = (can_chip_t)golden_value(g, "chip"),
      .rate_hz = (uint16_t)golden_value(g, "rate_hz"),
      .error_count = (uint8_t)golden_value(g, "error_count"),
  };
  for (unsigned i = 0; i < sizeof(flags) / sizeof(flags[0]); ++i) {
    if (golden_value(g, flags[i]) != 0.0) heartbeat.status |= (uint16_t)(1u << i);
  }
  assert_int_equal(golden_value(g, "fw_version_major"), NODE_FIRMWARE_VERSION_MAJOR);
  can_frame_t frame;
  can_protocol_pack_heartbeat((uint8_t)g->node_id, &heartbeat, &frame);
  assert_frame_equal(&frame, &g->frame);
}

static void check_reply(const golden_line_t *const g) {
  const can_reply_t reply = {
      .command = (uint8_t)golden_value(g, "command"),
      .result = (can_result_t)golden_value(g, "result"),
      .rate_hz = (uint16_t)golden_value(g, "rate_hz"),
      .acc_range_g = (uint8_t)golden_value(g, "acc_range_g"),
      .gyro_range_dps = (uint16_t)golden_value(g, "gyro_range_dps"),
      .mode = (node_mode_t)golden_value(g, "mode"),
      .running = golden_value(g, "running") != 0.0,
  };
  can_frame_t frame;
  can_protocol_pack_reply((uint8_t)g->node_id, &reply, &frame);
  assert_frame_equal(&frame, &g->frame);
}

static void check_received(const golden_line_t *const g) {
  if (strcmp(g->message, "Sync") == 0) {
    assert_int_equal(can_protocol_classify(17, &g->frame), CAN_RX_SYNC);
    assert_int_equal(can_protocol_unpack_sync(&g->frame), golden_value(g, "sync_seq"));
    return;
  }
  can_command_t command;
  assert_int_equal(can_protocol_classify((uint8_t)g->node_id, &g->frame), CAN_RX_COMMAND);
  assert_int_equal(can_protocol_classify((uint8_t)(g->node_id + 1), &g->frame), CAN_RX_IGNORED);
  assert_int_equal(can_protocol_unpack_command(&g->frame, &command), CAN_RESULT_OK);
  assert_int_equal(command.code, golden_value(g, "command"));
  if (command.code == CAN_COMMAND_SET_RATE) assert_int_equal(command.rate_hz, golden_value(g, "rate_hz"));
  if (command.code == CAN_COMMAND_SET_MODE) assert_int_equal(command.mode, golden_value(g, "mode"));
  if (command.code == CAN_COMMAND_SET_RANGES) {
    assert_int_equal(command.acc_range_g, golden_value(g, "acc_range_g"));
    assert_int_equal(command.gyro_range_dps, golden_value(g, "gyro_range_dps"));
  }
}

static void test_every_golden_frame(void **state) {
  (void)state;
  /* Fixture */
  FILE *file = fopen(FIRMWARE_GOLDEN_DIR "/can_frames.txt", "r");
  assert_non_null(file);
  char line[512];
  golden_line_t g, quat;
  int checked = 0;
  bool have_quat = false;
  /* Test / Assert: each line by the node's own functions */
  while (fgets(line, sizeof(line), file)) {
    if (!golden_parse(line, &g)) continue;
    if (strcmp(g.message, "ImuQuat") == 0) {
      quat = g;
      have_quat = true;
      continue;
    }
    if (strcmp(g.message, "ImuAccel") == 0) {
      assert_true(have_quat);
      check_sample(&quat, &g);
      have_quat = false;
    } else if (strcmp(g.message, "Heartbeat") == 0) {
      check_heartbeat(&g);
    } else if (strcmp(g.message, "CommandReply") == 0) {
      check_reply(&g);
    } else if (strcmp(g.message, "SyncReport") == 0) {
      can_frame_t frame;
      can_protocol_pack_sync_report((uint8_t)g.node_id, (uint8_t)golden_value(&g, "sync_seq"),
                                    (uint32_t)golden_value(&g, "rx_time_us"), &frame);
      assert_frame_equal(&frame, &g.frame);
    } else {
      check_received(&g);
    }
    checked++;
  }
  fclose(file);
  assert_true(checked >= 15);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_every_golden_frame)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
