/* SLCAN framing: frames round-trip through text, commands are answered, and bad lines are
 * refused with BEL and counted without losing the frames that follow. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>

#include <cmocka.h>

#include "slcan.h"

/* Feeds `text` and returns the last event; copies the frame and the reply seen. */
static slcan_event_t feed(slcan_decoder_t *const decoder, const char *text, can_frame_t *const frame,
                          char reply[SLCAN_MAX_REPLY], size_t *const reply_length) {
  slcan_event_t last = SLCAN_NONE;
  for (; *text; ++text) {
    const slcan_event_t event = slcan_decoder_push(decoder, *text, frame, reply, reply_length);
    if (event != SLCAN_NONE) last = event;
  }
  return last;
}

static void test_encodes_the_lawicel_text(void **state) {
  (void)state;
  const can_frame_t frame = {.id = 0x705, .length = 3, .data = {0x32, 0x01, 0xAB}};
  char text[SLCAN_MAX_LINE];
  const size_t n = slcan_encode(&frame, text, sizeof(text));
  assert_int_equal(n, 12);
  assert_memory_equal(text, "t7053" "3201AB\r", n);
}

static void test_refuses_to_encode_what_does_not_fit(void **state) {
  (void)state;
  const can_frame_t frame = {.id = 0x100, .length = 8};
  const can_frame_t bad_id = {.id = 0x800, .length = 0};
  char text[SLCAN_MAX_LINE];
  assert_int_equal(slcan_encode(&frame, text, 21), 0); /* needs 22 */
  assert_int_equal(slcan_encode(&frame, text, 22), 22);
  assert_int_equal(slcan_encode(&bad_id, text, sizeof(text)), 0);
}

static void test_frames_round_trip_once_open(void **state) {
  (void)state;
  slcan_decoder_t decoder;
  slcan_decoder_init(&decoder);
  const can_frame_t sent = {.id = 0x605, .length = 8, .data = {3, 0xC8, 0, 0, 0, 0, 0, 0xFF}};
  char text[SLCAN_MAX_LINE + 1] = {0};
  slcan_encode(&sent, text, SLCAN_MAX_LINE);
  can_frame_t got;
  char reply[SLCAN_MAX_REPLY];
  size_t reply_length;
  /* Closed: refused. */
  assert_int_equal(feed(&decoder, text, &got, reply, &reply_length), SLCAN_ERROR);
  assert_int_equal(reply[0], '\a');
  /* python-can's opening: close, bit rate, an empty line, open. */
  assert_int_equal(feed(&decoder, "C\rS8\r\rO\r", &got, reply, &reply_length), SLCAN_COMMAND);
  assert_true(decoder.open);
  assert_int_equal(feed(&decoder, text, &got, reply, &reply_length), SLCAN_FRAME);
  assert_int_equal(got.id, sent.id);
  assert_int_equal(got.length, sent.length);
  assert_memory_equal(got.data, sent.data, 8);
  assert_int_equal(feed(&decoder, "t0801c9\r", &got, reply, &reply_length), SLCAN_FRAME);
  assert_int_equal(got.data[0], 0xC9); /* lower-case hex accepted */
  assert_int_equal(decoder.errors, 1);
}

static void test_malformed_lines_are_refused_and_counted(void **state) {
  (void)state;
  slcan_decoder_t decoder;
  slcan_decoder_init(&decoder);
  can_frame_t got;
  char reply[SLCAN_MAX_REPLY];
  size_t reply_length;
  feed(&decoder, "O\r", &got, reply, &reply_length);
  static const char *const bad[] = {
      "t1239\r",              /* length digit above 8 */
      "t123200\r",            /* says 2 bytes, carries one */
      "t1230\r\0",            /* fine: tested below */
      "tXYZ0\r",              /* not hex */
      "t800\r",               /* too short */
      "T123456781AA\r",       /* extended frames: the protocol has none */
      "r1230\r",              /* remote frames: none either */
      "Z\r",                  /* unknown command */
      "S9\r",                 /* unknown bit rate */
      "t1238000000000000000000000000000000000000\r", /* longer than any line */
  };
  int refused = 0;
  for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); ++i) {
    const slcan_event_t event = feed(&decoder, bad[i], &got, reply, &reply_length);
    if (i == 2) {
      assert_int_equal(event, SLCAN_FRAME);
      assert_int_equal(got.length, 0);
      continue;
    }
    assert_int_equal(event, SLCAN_ERROR);
    assert_int_equal(reply_length, 1);
    assert_int_equal(reply[0], '\a');
    refused++;
  }
  assert_int_equal(decoder.errors, (uint32_t)refused);
  /* The next good line still decodes. */
  assert_int_equal(feed(&decoder, "t080101\r", &got, reply, &reply_length), SLCAN_FRAME);
  assert_int_equal(got.id, 0x080);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_encodes_the_lawicel_text),
      cmocka_unit_test(test_refuses_to_encode_what_does_not_fit),
      cmocka_unit_test(test_frames_round_trip_once_open),
      cmocka_unit_test(test_malformed_lines_are_refused_and_counted),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
