/* SLCAN (LAWICEL ASCII) framing of classic CAN frames over a serial line, the node's
 * bus where no CAN controller exists (the QEMU board's UART; any USB-serial adapter).
 *
 * Frames: `tIIILDD..\r` (11-bit id: 3 hex digits, length digit, 2 hex digits per byte).
 * Commands from the host: `O\r` open, `C\r` close, `Sn\r` bit rate, `V\r`/`N\r`
 * version/serial, `F\r` status flags; answered `\r` (ok) or `\a` (refused). An empty
 * line (python-can sends one when no data bit rate is set) is ignored.
 * Extended (`T`) and remote (`r`, `R`) frames are refused: the protocol has none.
 */
#ifndef FIRMWARE_CORE_SLCAN_H
#define FIRMWARE_CORE_SLCAN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "can_frame.h"

#define SLCAN_MAX_LINE 32u /* bytes: the longest line, `t` + 3 + 1 + 16 + `\r` = 22 */
#define SLCAN_MAX_REPLY 8u /* bytes: the longest answer to a command (`V0101\r`) */

/* Writes the SLCAN text of `frame` into `text` (no terminating NUL); returns its length
 * in bytes, or 0 when `capacity` is too small or the frame is invalid. */
size_t slcan_encode(const can_frame_t *const frame, char *const text, size_t capacity);

typedef enum {
  SLCAN_NONE = 0,     /* the line is not complete yet */
  SLCAN_FRAME,        /* a data frame arrived: see `frame` */
  SLCAN_COMMAND,      /* a command was handled: send `reply` */
  SLCAN_ERROR,        /* a malformed or refused line: send `reply` (`\a`) */
} slcan_event_t;

typedef struct {
  char line[SLCAN_MAX_LINE];
  size_t length;       /* bytes in `line` */
  bool overflowed;     /* the line grew past SLCAN_MAX_LINE: refused at its `\r` */
  bool open;           /* the host sent `O`: frames flow both ways */
  uint32_t errors;     /* malformed or refused lines since start-up */
} slcan_decoder_t;

void slcan_decoder_init(slcan_decoder_t *const decoder);

/* Feeds one received character. On SLCAN_FRAME `frame` holds the frame; on
 * SLCAN_COMMAND or SLCAN_ERROR `reply` holds `reply_length` bytes to send back. */
slcan_event_t slcan_decoder_push(slcan_decoder_t *const decoder, char character,
                                 can_frame_t *const frame, char reply[SLCAN_MAX_REPLY],
                                 size_t *const reply_length);

#endif /* FIRMWARE_CORE_SLCAN_H */
