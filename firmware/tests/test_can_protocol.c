/* The node's protocol layer beyond the golden vectors: out-of-range values are clamped to
 * the signals' ranges, q and -q pack alike, NaN cannot reach the bus, and received frames
 * are classified by identifier and length. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>

#include <cmocka.h>

#include "can_protocol.h"

static void pack(const node_output_t *const out, struct mocap_imu_imu_quat_t *const quat,
                 struct mocap_imu_imu_accel_t *const accel) {
  can_frame_t quat_frame, accel_frame;
  can_protocol_pack_sample(9, out, &quat_frame, &accel_frame);
  assert_int_equal(quat_frame.id, 0x109);
  assert_int_equal(accel_frame.id, 0x149);
  assert_int_equal(mocap_imu_imu_quat_unpack(quat, quat_frame.data, quat_frame.length), 0);
  assert_int_equal(mocap_imu_imu_accel_unpack(accel, accel_frame.data, accel_frame.length), 0);
}

static void test_identity_and_its_negative_pack_alike(void **state) {
  (void)state;
  const node_output_t plus = {.q_wxyz = {1.0f, 0.0f, 0.0f, 0.0f}};
  const node_output_t minus = {.q_wxyz = {-1.0f, -0.0f, 0.0f, 0.0f}};
  struct mocap_imu_imu_quat_t a, b;
  struct mocap_imu_imu_accel_t accel;
  pack(&plus, &a, &accel);
  pack(&minus, &b, &accel);
  assert_int_equal(a.q_w, 8191); /* +1.0 is out of the 14-bit range: the largest value */
  assert_int_equal(b.q_w, 8191);
  assert_int_equal(b.q_x, 0);
}

static void test_values_beyond_a_signal_clamp_and_nan_becomes_zero(void **state) {
  (void)state;
  const node_output_t out = {
      .q_wxyz = {0.5f, -1.5f, NAN, 0.25f},
      .acc_mps2 = {300.0f, -300.0f, INFINITY},
      .time_us = 0x12345678u,
  };
  struct mocap_imu_imu_quat_t quat;
  struct mocap_imu_imu_accel_t accel;
  pack(&out, &quat, &accel);
  assert_int_equal(quat.q_x, -8192);
  assert_int_equal(quat.q_y, 0);
  assert_int_equal(quat.q_z, 2048);
  assert_int_equal(accel.a_x, 16383);
  assert_int_equal(accel.a_y, -16384);
  assert_int_equal(accel.a_z, 16383);
  assert_int_equal(accel.sample_time_us, 0x5678);
}

static void test_quantisation_is_within_half_a_step(void **state) {
  (void)state;
  const node_output_t out = {.q_wxyz = {0.70710678f, 0.1f, -0.3f, 0.62f},
                             .acc_mps2 = {9.80665f, -0.01f, 3.3f}};
  struct mocap_imu_imu_quat_t quat;
  struct mocap_imu_imu_accel_t accel;
  pack(&out, &quat, &accel);
  assert_true(fabsf(mocap_imu_imu_quat_q_w_decode(quat.q_w) - out.q_wxyz[0]) <= 0.5f / 8192.0f);
  assert_true(fabsf(mocap_imu_imu_quat_q_z_decode(quat.q_z) - out.q_wxyz[3]) <= 0.5f / 8192.0f);
  assert_true(fabsf(mocap_imu_imu_accel_a_x_decode(accel.a_x) - out.acc_mps2[0]) <= 0.5f / 64.0f);
  assert_true(fabsf(mocap_imu_imu_accel_a_y_decode(accel.a_y) - out.acc_mps2[1]) <= 0.5f / 64.0f);
}

static void test_received_frames_are_classified_by_id_and_length(void **state) {
  (void)state;
  can_frame_t frame = {.id = 0x080, .length = 1};
  assert_int_equal(can_protocol_classify(5, &frame), CAN_RX_SYNC);
  frame.length = 2;
  assert_int_equal(can_protocol_classify(5, &frame), CAN_RX_MALFORMED);
  frame = (can_frame_t){.id = 0x605, .length = 8, .data = {1}};
  assert_int_equal(can_protocol_classify(5, &frame), CAN_RX_COMMAND);
  assert_int_equal(can_protocol_classify(6, &frame), CAN_RX_IGNORED);
  frame.length = 3;
  assert_int_equal(can_protocol_classify(5, &frame), CAN_RX_MALFORMED);
  frame = (can_frame_t){.id = 0x105, .length = 8}; /* another node's sample */
  assert_int_equal(can_protocol_classify(5, &frame), CAN_RX_IGNORED);
}

static void test_unknown_command_codes_are_named(void **state) {
  (void)state;
  can_command_t command;
  for (unsigned code = 0; code < 256; ++code) {
    const can_frame_t frame = {.id = 0x605, .length = 8, .data = {(uint8_t)code, 0xFF, 0xFF}};
    const can_result_t result = can_protocol_unpack_command(&frame, &command);
    const bool known = code >= CAN_COMMAND_START && code <= CAN_COMMAND_SET_MODE;
    assert_int_equal(result, known ? CAN_RESULT_OK : CAN_RESULT_UNKNOWN_COMMAND);
    assert_int_equal(command.code, code);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_identity_and_its_negative_pack_alike),
      cmocka_unit_test(test_values_beyond_a_signal_clamp_and_nan_becomes_zero),
      cmocka_unit_test(test_quantisation_is_within_half_a_step),
      cmocka_unit_test(test_received_frames_are_classified_by_id_and_length),
      cmocka_unit_test(test_unknown_command_codes_are_named),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
