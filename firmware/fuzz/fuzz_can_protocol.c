/* libFuzzer target: the CAN frame decoders of can_protocol.c for any frame a controller
 * can hand over (any 11-bit identifier, a length code 0..15, any data), for any node id.
 * Input: [node id][id low][id high][length][8 data bytes], repeated. Checks: classify is
 * consistent with the frame's identifier and length, a command unpacks to one of its
 * results, and what the node packs back is a valid classic frame. */
#include <stdlib.h>
#include <string.h>

#include "can_protocol.h"

static void check_frame(const can_frame_t *const frame) {
  if (frame->id > 0x7FFu || frame->length > CAN_FRAME_MAX_DATA) abort();
}

static void decode(uint8_t node_id, const can_frame_t *const frame) {
  const can_rx_kind_t kind = can_protocol_classify(node_id, frame);
  const bool ours = frame->id == CAN_ID_SYNC || frame->id == CAN_BASE_COMMAND + node_id;
  if ((kind == CAN_RX_IGNORED) == ours) abort();
  if (kind == CAN_RX_SYNC) (void)can_protocol_unpack_sync(frame);
  if (kind != CAN_RX_COMMAND) return;
  can_command_t command;
  const can_result_t result = can_protocol_unpack_command(frame, &command);
  if (result != CAN_RESULT_OK && result != CAN_RESULT_UNKNOWN_COMMAND) abort();
  const can_reply_t reply = {.command = command.code, .result = result,
                             .rate_hz = command.rate_hz, .acc_range_g = command.acc_range_g,
                             .gyro_range_dps = command.gyro_range_dps,
                             .mode = (node_mode_t)(command.mode & 1u)};
  can_frame_t packed;
  can_protocol_pack_reply(node_id & CAN_NODE_ID_MASK, &reply, &packed);
  check_frame(&packed);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  for (size_t at = 0; at + 12 <= size; at += 12) {
    can_frame_t frame;
    const uint8_t node_id = data[at];
    frame.id = (uint16_t)((data[at + 1] | (data[at + 2] << 8)) & 0x7FFu);
    frame.length = data[at + 3] & 0x0Fu; /* a DLC above 8 is still 8 bytes of data */
    memcpy(frame.data, data + at + 4, CAN_FRAME_MAX_DATA);
    decode(node_id, &frame);
  }
  return 0;
}
