/* libFuzzer target: the SLCAN line decoder (slcan.c) fed any bytes from the serial line.
 * Checks: a decoded frame is a valid classic frame whose SLCAN text decodes back to it;
 * a reply fits SLCAN_MAX_REPLY; the line buffer never passes SLCAN_MAX_LINE. */
#include <stdlib.h>
#include <string.h>

#include "slcan.h"

static void round_trip(const can_frame_t *const frame) {
  if (frame->id > 0x7FFu || frame->length > CAN_FRAME_MAX_DATA) abort();
  char text[SLCAN_MAX_LINE];
  const size_t length = slcan_encode(frame, text, sizeof(text));
  if (length == 0) abort();
  slcan_decoder_t again;
  slcan_decoder_init(&again);
  again.open = true;
  can_frame_t back;
  char reply[SLCAN_MAX_REPLY];
  size_t reply_length = 0;
  slcan_event_t event = SLCAN_NONE;
  for (size_t i = 0; i < length; ++i) event = slcan_decoder_push(&again, text[i], &back, reply, &reply_length);
  if (event != SLCAN_FRAME || back.id != frame->id || back.length != frame->length ||
      memcmp(back.data, frame->data, frame->length) != 0) {
    abort();
  }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  slcan_decoder_t decoder;
  slcan_decoder_init(&decoder);
  for (size_t i = 0; i < size; ++i) {
    can_frame_t frame;
    char reply[SLCAN_MAX_REPLY];
    size_t reply_length = SLCAN_MAX_REPLY + 1;
    const slcan_event_t event = slcan_decoder_push(&decoder, (char)data[i], &frame, reply, &reply_length);
    if (reply_length > SLCAN_MAX_REPLY || decoder.length > SLCAN_MAX_LINE) abort();
    if ((event == SLCAN_COMMAND || event == SLCAN_ERROR) && reply_length == 0) abort();
    if (event == SLCAN_FRAME) round_trip(&frame);
  }
  return 0;
}
