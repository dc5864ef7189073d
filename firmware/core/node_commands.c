/* Frames the node receives: Sync (answered with the arrival time) and Command (checked,
 * applied, answered with the configuration after it). */
#include <stddef.h>

#include "node_internal.h"

static bool node_acc_range_valid(uint8_t g) { return g == 2 || g == 4 || g == 8 || g == 16; }

static bool node_gyro_range_valid(uint16_t dps) {
  return dps == 250 || dps == 500 || dps == 1000 || dps == 2000;
}

static bool node_rate_valid(const node_t *const node, uint16_t rate_hz) {
  const uint16_t odr_hz = node->settings.imu_odr_hz;
  return rate_hz > 0 && rate_hz <= NODE_MAX_RATE_HZ && rate_hz <= odr_hz;
}

static can_result_t node_apply_command(node_t *const node, const can_command_t *const command) {
  switch (command->code) {
    case CAN_COMMAND_START:
      node->running = true;
      node_sensors_configure_output(node);
      return CAN_RESULT_OK;
    case CAN_COMMAND_STOP:
      node->running = false;
      return CAN_RESULT_OK;
    case CAN_COMMAND_SET_RATE:
      if (!node_rate_valid(node, command->rate_hz)) return CAN_RESULT_BAD_VALUE;
      if (node->running) return CAN_RESULT_BUSY;
      node->rate_hz = command->rate_hz;
      node_sensors_configure_output(node);
      return CAN_RESULT_OK;
    case CAN_COMMAND_SET_RANGES:
      if (!node_acc_range_valid(command->acc_range_g) ||
          !node_gyro_range_valid(command->gyro_range_dps)) {
        return CAN_RESULT_BAD_VALUE;
      }
      if (node->running) return CAN_RESULT_BUSY;
      node->acc_range_g = command->acc_range_g;
      node->gyro_range_dps = command->gyro_range_dps;
      node->imu_ready = false; /* configured again with the new ranges at once */
      node->next_imu_probe_us = node->now_us;
      return CAN_RESULT_OK;
    case CAN_COMMAND_SET_MODE:
      if (command->mode > NODE_MODE_9D) return CAN_RESULT_BAD_VALUE;
      node->mode = (node_mode_t)command->mode;
      return CAN_RESULT_OK;
    default:
      return CAN_RESULT_UNKNOWN_COMMAND;
  }
}

static void node_reply(node_t *const node, uint8_t code, can_result_t result) {
  const can_reply_t reply = {
      .command = code,
      .result = result,
      .rate_hz = node->rate_hz,
      .acc_range_g = node->acc_range_g,
      .gyro_range_dps = node->gyro_range_dps,
      .mode = node->mode,
      .running = node->running,
  };
  can_frame_t frame;
  can_protocol_pack_reply(node->settings.node_id, &reply, &frame);
  node_queue_frame(node, &frame, node->now_us, false);
}

static void node_refused(node_t *const node, uint16_t status_bit) {
  node->status |= status_bit;
  node->error_count++;
}

static void node_command(node_t *const node, const can_frame_t *const frame) {
  can_command_t command;
  can_result_t result = can_protocol_unpack_command(frame, &command);
  if (result == CAN_RESULT_OK) result = node_apply_command(node, &command);
  if (result != CAN_RESULT_OK) node_refused(node, CAN_STATUS_COMMAND_REFUSED);
  node_reply(node, command.code, result);
}

static void node_sync(node_t *const node, const can_frame_t *const frame, uint32_t rx_time_us) {
  can_frame_t report;
  can_protocol_pack_sync_report(node->settings.node_id, can_protocol_unpack_sync(frame),
                                rx_time_us, &report);
  node_queue_frame(node, &report, rx_time_us, false);
  node->last_sync_us = rx_time_us;
  node->sync_seen = true;
}

void node_handle_frame(node_t *const node, const can_frame_t *const frame, uint32_t rx_time_us) {
  switch (can_protocol_classify(node->settings.node_id, frame)) {
    case CAN_RX_SYNC:
      node_sync(node, frame, rx_time_us);
      break;
    case CAN_RX_COMMAND:
      node_command(node, frame);
      break;
    case CAN_RX_MALFORMED:
      node_refused(node, CAN_STATUS_FRAME_MALFORMED);
      if (frame->id != CAN_ID_SYNC) {
        node_reply(node, frame->length > 0 ? frame->data[0] : 0, CAN_RESULT_BAD_LENGTH);
      }
      break;
    case CAN_RX_IGNORED:
      break;
  }
}
