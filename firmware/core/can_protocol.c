/* The node's side of the CAN protocol: see can_protocol.h. */
#include "can_protocol.h"

#include <string.h>

/* Physical value clamped to [low, high]; NaN becomes 0. */
static float can_clamp(float value, float low, float high) {
  if (!(value == value)) return 0.0f;
  return value < low ? low : (value > high ? high : value);
}

static void can_frame_set(can_frame_t *const frame, uint32_t id, int length) {
  frame->id = (uint16_t)id;
  frame->length = (uint8_t)(length < 0 ? 0 : length);
}

void can_protocol_pack_sample(uint8_t node_id, const node_output_t *const output,
                              can_frame_t *const quat_frame, can_frame_t *const accel_frame) {
  /* q and -q are one rotation: send w >= 0, so +1.0 (out of range) clamps only at w. */
  const float sign = output->q_wxyz[0] < 0.0f ? -1.0f : 1.0f;
  const float q_max = 8191.0f / 8192.0f;
  struct mocap_imu_imu_quat_t quat = {
      .q_w = mocap_imu_imu_quat_q_w_encode(can_clamp(sign * output->q_wxyz[0], -1.0f, q_max)),
      .q_x = mocap_imu_imu_quat_q_x_encode(can_clamp(sign * output->q_wxyz[1], -1.0f, q_max)),
      .q_y = mocap_imu_imu_quat_q_y_encode(can_clamp(sign * output->q_wxyz[2], -1.0f, q_max)),
      .q_z = mocap_imu_imu_quat_q_z_encode(can_clamp(sign * output->q_wxyz[3], -1.0f, q_max)),
      .seq = output->seq,
  };
  can_frame_set(quat_frame, CAN_BASE_IMU_QUAT + node_id,
                mocap_imu_imu_quat_pack(quat_frame->data, &quat, sizeof(quat_frame->data)));

  const float a_max = 16383.0f / 64.0f; /* m/s^2: 15 bits at 2^-6 */
  struct mocap_imu_imu_accel_t accel = {
      .a_x = mocap_imu_imu_accel_a_x_encode(can_clamp(output->acc_mps2[0], -256.0f, a_max)),
      .a_y = mocap_imu_imu_accel_a_y_encode(can_clamp(output->acc_mps2[1], -256.0f, a_max)),
      .a_z = mocap_imu_imu_accel_a_z_encode(can_clamp(output->acc_mps2[2], -256.0f, a_max)),
      .orientation_invalid = output->orientation_invalid,
      .acc_clipped = output->acc_clipped,
      .mag_disturbed = output->mag_disturbed,
      .sample_time_us = (uint16_t)(output->time_us & 0xFFFFu),
  };
  can_frame_set(accel_frame, CAN_BASE_IMU_ACCEL + node_id,
                mocap_imu_imu_accel_pack(accel_frame->data, &accel, sizeof(accel_frame->data)));
}

void can_protocol_pack_heartbeat(uint8_t node_id, const can_heartbeat_t *const heartbeat,
                                 can_frame_t *const frame) {
  const uint16_t s = heartbeat->status;
  struct mocap_imu_heartbeat_t message = {
      .state = (uint8_t)heartbeat->state,
      .mode = (uint8_t)heartbeat->mode,
      .synced = heartbeat->synced,
      .chip = (uint8_t)heartbeat->chip,
      .rate_hz = heartbeat->rate_hz,
      .imu_nack = (s & CAN_STATUS_IMU_NACK) != 0,
      .mag_nack = (s & CAN_STATUS_MAG_NACK) != 0,
      .fifo_overflow = (s & CAN_STATUS_FIFO_OVERFLOW) != 0,
      .imu_stuck = (s & CAN_STATUS_IMU_STUCK) != 0,
      .mag_stuck = (s & CAN_STATUS_MAG_STUCK) != 0,
      .command_refused = (s & CAN_STATUS_COMMAND_REFUSED) != 0,
      .frame_malformed = (s & CAN_STATUS_FRAME_MALFORMED) != 0,
      .self_test_failed = (s & CAN_STATUS_SELF_TEST_FAILED) != 0,
      .acc_clipped = (s & CAN_STATUS_ACC_CLIPPED) != 0,
      .mag_disturbed = (s & CAN_STATUS_MAG_DISTURBED) != 0,
      .tx_overflow = (s & CAN_STATUS_TX_OVERFLOW) != 0,
      .fw_version_major = NODE_FIRMWARE_VERSION_MAJOR,
      .fw_version_minor = NODE_FIRMWARE_VERSION_MINOR,
      .error_count = heartbeat->error_count,
  };
  can_frame_set(frame, CAN_BASE_HEARTBEAT + node_id,
                mocap_imu_heartbeat_pack(frame->data, &message, sizeof(frame->data)));
}

void can_protocol_pack_reply(uint8_t node_id, const can_reply_t *const reply,
                             can_frame_t *const frame) {
  struct mocap_imu_command_reply_t message = {
      .command = reply->command,
      .result = (uint8_t)reply->result,
      .rate_hz = reply->rate_hz,
      .acc_range_g = reply->acc_range_g,
      .gyro_range_dps = reply->gyro_range_dps,
      .mode = (uint8_t)reply->mode,
      .running = reply->running,
  };
  can_frame_set(frame, CAN_BASE_COMMAND_REPLY + node_id,
                mocap_imu_command_reply_pack(frame->data, &message, sizeof(frame->data)));
}

void can_protocol_pack_sync_report(uint8_t node_id, uint8_t sync_seq, uint32_t rx_time_us,
                                   can_frame_t *const frame) {
  struct mocap_imu_sync_report_t message = {.sync_seq = sync_seq, .rx_time_us = rx_time_us};
  can_frame_set(frame, CAN_BASE_SYNC_REPORT + node_id,
                mocap_imu_sync_report_pack(frame->data, &message, sizeof(frame->data)));
}

can_rx_kind_t can_protocol_classify(uint8_t node_id, const can_frame_t *const frame) {
  if (frame->id == CAN_ID_SYNC) {
    return frame->length == MOCAP_IMU_SYNC_LENGTH ? CAN_RX_SYNC : CAN_RX_MALFORMED;
  }
  if (frame->id == CAN_BASE_COMMAND + node_id) {
    return frame->length == MOCAP_IMU_COMMAND_LENGTH ? CAN_RX_COMMAND : CAN_RX_MALFORMED;
  }
  return CAN_RX_IGNORED;
}

uint8_t can_protocol_unpack_sync(const can_frame_t *const frame) {
  struct mocap_imu_sync_t message;
  mocap_imu_sync_unpack(&message, frame->data, frame->length);
  return message.sync_seq;
}

can_result_t can_protocol_unpack_command(const can_frame_t *const frame,
                                         can_command_t *const command) {
  struct mocap_imu_command_t message;
  memset(command, 0, sizeof(*command));
  if (mocap_imu_command_unpack(&message, frame->data, frame->length) < 0) {
    return CAN_RESULT_BAD_LENGTH;
  }
  command->code = message.command;
  command->rate_hz = message.rate_hz;
  command->acc_range_g = message.acc_range_g;
  command->gyro_range_dps = message.gyro_range_dps;
  command->mode = message.mode;
  if (message.command < CAN_COMMAND_START || message.command > CAN_COMMAND_SET_MODE) {
    return CAN_RESULT_UNKNOWN_COMMAND;
  }
  return CAN_RESULT_OK;
}
