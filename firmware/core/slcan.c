/* SLCAN (LAWICEL) text framing: see slcan.h. */
#include "slcan.h"

#include <string.h>

static const char slcan_hex_digits[] = "0123456789ABCDEF";

/* The value of one hex digit (either case), or -1. */
static int slcan_hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

/* Parses `digits` hex digits of `text` into *value; false on a non-hex character. */
static bool slcan_parse_hex(const char *text, size_t digits, uint32_t *const value) {
  uint32_t result = 0;
  for (size_t i = 0; i < digits; ++i) {
    const int nibble = slcan_hex_value(text[i]);
    if (nibble < 0) return false;
    result = (result << 4) | (uint32_t)nibble;
  }
  *value = result;
  return true;
}

size_t slcan_encode(const can_frame_t *const frame, char *const text, size_t capacity) {
  if (frame->id > 0x7FFu || frame->length > CAN_FRAME_MAX_DATA) return 0;
  const size_t length = 1u + 3u + 1u + 2u * frame->length + 1u;
  if (capacity < length) return 0;
  size_t n = 0;
  text[n++] = 't';
  text[n++] = slcan_hex_digits[(frame->id >> 8) & 0xFu];
  text[n++] = slcan_hex_digits[(frame->id >> 4) & 0xFu];
  text[n++] = slcan_hex_digits[frame->id & 0xFu];
  text[n++] = (char)('0' + frame->length);
  for (size_t i = 0; i < frame->length; ++i) {
    text[n++] = slcan_hex_digits[frame->data[i] >> 4];
    text[n++] = slcan_hex_digits[frame->data[i] & 0xFu];
  }
  text[n++] = '\r';
  return n;
}

void slcan_decoder_init(slcan_decoder_t *const decoder) {
  memset(decoder, 0, sizeof(*decoder));
}

/* A `tIIIL<data>` line (without its `\r`) into *frame; false when malformed. */
static bool slcan_parse_frame(const char *line, size_t length, can_frame_t *const frame) {
  uint32_t id = 0;
  uint32_t dlc = 0;
  if (length < 5u || !slcan_parse_hex(line + 1, 3, &id) || id > 0x7FFu) return false;
  if (!slcan_parse_hex(line + 4, 1, &dlc) || dlc > CAN_FRAME_MAX_DATA) return false;
  if (length != 5u + 2u * dlc) return false;
  frame->id = (uint16_t)id;
  frame->length = (uint8_t)dlc;
  memset(frame->data, 0, sizeof(frame->data));
  for (uint32_t i = 0; i < dlc; ++i) {
    uint32_t byte = 0;
    if (!slcan_parse_hex(line + 5 + 2 * i, 2, &byte)) return false;
    frame->data[i] = (uint8_t)byte;
  }
  return true;
}

/* Answers a one-letter command line; false when the command is refused. */
static bool slcan_command(slcan_decoder_t *const decoder, const char *line, size_t length,
                          char reply[SLCAN_MAX_REPLY], size_t *const reply_length) {
  static const char version[] = "V0100\r"; /* hardware 01, software 00 */
  static const char serial[] = "NMCAP\r";
  const char *text = "\r";
  switch (line[0]) {
    case 'O': if (length != 1) return false; decoder->open = true; break;
    case 'C': if (length != 1) return false; decoder->open = false; break;
    case 'S': if (length != 2 || line[1] < '0' || line[1] > '8') return false; break;
    case 'V': if (length != 1) return false; text = version; break;
    case 'N': if (length != 1) return false; text = serial; break;
    case 'F': if (length != 1) return false; text = "F00\r"; break;
    default: return false;
  }
  *reply_length = strlen(text);
  memcpy(reply, text, *reply_length);
  return true;
}

/* Interprets a complete line (its `\r` not included). */
static slcan_event_t slcan_line(slcan_decoder_t *const decoder, can_frame_t *const frame,
                                char reply[SLCAN_MAX_REPLY], size_t *const reply_length) {
  const char *line = decoder->line;
  const size_t length = decoder->length;
  if (!decoder->overflowed && length == 0) return SLCAN_NONE; /* an empty line: nothing */
  if (!decoder->overflowed) {
    if (line[0] == 't') {
      if (decoder->open && slcan_parse_frame(line, length, frame)) return SLCAN_FRAME;
    } else if (slcan_command(decoder, line, length, reply, reply_length)) {
      return SLCAN_COMMAND;
    }
  }
  decoder->errors++;
  reply[0] = '\a';
  *reply_length = 1;
  return SLCAN_ERROR;
}

slcan_event_t slcan_decoder_push(slcan_decoder_t *const decoder, char character,
                                 can_frame_t *const frame, char reply[SLCAN_MAX_REPLY],
                                 size_t *const reply_length) {
  *reply_length = 0;
  if (character == '\r') {
    const slcan_event_t event = slcan_line(decoder, frame, reply, reply_length);
    decoder->length = 0;
    decoder->overflowed = false;
    return event;
  }
  if (character == '\n' && decoder->length == 0) return SLCAN_NONE; /* CRLF senders */
  if (decoder->length < SLCAN_MAX_LINE) {
    decoder->line[decoder->length++] = character;
  } else {
    decoder->overflowed = true;
  }
  return SLCAN_NONE;
}
