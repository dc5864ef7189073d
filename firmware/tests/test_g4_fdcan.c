/* The production board's FDCAN logic on the host (boards/stm32g431kb): the nominal bit
 * timing computed from the kernel clock, the message RAM layout against RM0440, the
 * filter and frame elements, and the start-of-frame time conversion. The registers
 * themselves are not reachable here. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

/* The board's pure C, compiled into this test (boards/ is not in the host library). */
#include "../boards/stm32g431kb/g4_fdcan_ram.c"
#include "../boards/stm32g431kb/g4_fdcan_timing.c"

/* Every invariant of a computed timing, checked from its fields. */
static void assert_timing_valid(uint32_t kernel_hz, uint32_t bitrate_bps, uint16_t sample_permille,
                                const g4_fdcan_timing_t *const t) {
  assert_int_equal((uint64_t)t->prescaler * t->tq_per_bit * bitrate_bps, kernel_hz);
  assert_int_equal(t->tq_per_bit, 1u + t->tseg1_tq + t->tseg2_tq);
  assert_in_range(t->prescaler, 1u, G4_FDCAN_PRESCALER_MAX);
  assert_in_range(t->tseg1_tq, G4_FDCAN_TSEG1_MIN, G4_FDCAN_TSEG1_MAX);
  assert_in_range(t->tseg2_tq, G4_FDCAN_TSEG2_MIN, G4_FDCAN_TSEG2_MAX);
  assert_int_equal(t->sjw_tq, t->tseg2_tq);
  /* The sample point is within one quantum of the request. */
  const int64_t sample_x1000 = 1000 * (int64_t)(1u + t->tseg1_tq);
  const int64_t requested_x1000 = (int64_t)sample_permille * t->tq_per_bit;
  assert_true(sample_x1000 - requested_x1000 <= 1000 && requested_x1000 - sample_x1000 <= 1000);
}

static void test_timing_of_the_board(void **state) {
  (void)state;
  /* Fixture: the board's kernel clock and bus. */
  g4_fdcan_timing_t timing;
  /* Test */
  const bool ok = g4_fdcan_timing_compute(170000000u, 1000000u, 875u, &timing);
  /* Assert: the finest quanta (prescaler 1), and the register fields stored minus one. */
  assert_true(ok);
  assert_timing_valid(170000000u, 1000000u, 875u, &timing);
  assert_int_equal(timing.prescaler, 1u);
  const uint32_t nbtp = g4_fdcan_timing_nbtp(&timing);
  assert_int_equal((nbtp >> 25) + 1u, timing.sjw_tq);
  assert_int_equal(((nbtp >> 16) & 0x1FFu) + 1u, timing.prescaler);
  assert_int_equal(((nbtp >> 8) & 0xFFu) + 1u, timing.tseg1_tq);
  assert_int_equal((nbtp & 0x7Fu) + 1u, timing.tseg2_tq);
}

static void test_timing_of_other_clocks(void **state) {
  (void)state;
  /* Fixture: clocks and rates that divide, some needing a prescaler above 1. */
  static const uint32_t cases[][3] = {{80000000u, 500000u, 875u}, {160000000u, 1000000u, 800u},
                                      {40000000u, 250000u, 875u}, {170000000u, 125000u, 875u},
                                      {8000000u, 1000000u, 750u}};
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    g4_fdcan_timing_t timing;
    /* Test */
    const bool ok = g4_fdcan_timing_compute(cases[i][0], cases[i][1], (uint16_t)cases[i][2], &timing);
    /* Assert */
    assert_true(ok);
    assert_timing_valid(cases[i][0], cases[i][1], (uint16_t)cases[i][2], &timing);
  }
}

static void test_timing_refuses_what_cannot_be_met(void **state) {
  (void)state;
  /* Fixture */
  g4_fdcan_timing_t timing;
  /* Test and Assert: no exact division, too few quanta, above classic CAN, bad point. */
  assert_false(g4_fdcan_timing_compute(170000000u, 999999u, 875u, &timing));
  assert_false(g4_fdcan_timing_compute(4000000u, 1000000u, 875u, &timing));
  assert_false(g4_fdcan_timing_compute(170000000u, 2000000u, 875u, &timing));
  assert_false(g4_fdcan_timing_compute(170000000u, 1000000u, 1000u, &timing));
  assert_false(g4_fdcan_timing_compute(170000000u, 0u, 875u, &timing));
}

static void test_tolerance_follows_iso_11898(void **state) {
  (void)state;
  /* Fixture: 10 quanta, tseg1 7, tseg2 2, SJW 2. By SJW: 2 / (20 * 10) = 10000 ppm; by
   * phase: 2 / (2 * (13 * 10 - 2)) = 7812.5 ppm, the smaller. */
  const g4_fdcan_timing_t timing = {.prescaler = 1u, .tseg1_tq = 7u, .tseg2_tq = 2u,
                                    .sjw_tq = 2u, .tq_per_bit = 10u};
  /* Test */
  const uint32_t ppm = g4_fdcan_timing_tolerance_ppm(&timing);
  /* Assert */
  assert_int_equal(ppm, 7812u);
}

static void test_ram_layout_is_rm0440s(void **state) {
  (void)state;
  /* Fixture: RM0440's message RAM map of one instance (212 words). Test and Assert. */
  assert_int_equal(G4_FDCAN_RAM_STD_FILTER_OFFSET, 0x000u);
  assert_int_equal(G4_FDCAN_RAM_EXT_FILTER_OFFSET, 0x070u);
  assert_int_equal(G4_FDCAN_RAM_RX_FIFO0_OFFSET, 0x0B0u);
  assert_int_equal(G4_FDCAN_RAM_RX_FIFO1_OFFSET, 0x188u);
  assert_int_equal(G4_FDCAN_RAM_TX_EVENT_OFFSET, 0x260u);
  assert_int_equal(G4_FDCAN_RAM_TX_BUFFER_OFFSET, 0x278u);
  assert_int_equal(G4_FDCAN_RAM_INSTANCE_BYTES, 212u * 4u);
  assert_int_equal(g4_fdcan_ram_rx_fifo0_offset(2u), 0x0B0u + 2u * 72u);
  assert_int_equal(g4_fdcan_ram_tx_buffer_offset(2u) + G4_FDCAN_RAM_ELEMENT_BYTES,
                   G4_FDCAN_RAM_INSTANCE_BYTES);
}

static void test_filter_passes_sync_and_own_command(void **state) {
  (void)state;
  /* Fixture */
  const uint16_t sync = 0x080u, command = (uint16_t)(0x600u + 42u);
  /* Test */
  const uint32_t element = g4_fdcan_ram_filter_dual_to_fifo0(sync, command);
  /* Assert: SFT = 01 (dual ID), SFEC = 001 (FIFO 0), SFID1, SFID2. */
  assert_int_equal(element >> 30, 1u);
  assert_int_equal((element >> 27) & 0x7u, 1u);
  assert_int_equal((element >> 16) & 0x7FFu, sync);
  assert_int_equal(element & 0x7FFu, command);
}

static void test_tx_element_packs_a_classic_frame(void **state) {
  (void)state;
  /* Fixture */
  const can_frame_t frame = {.id = 0x72Au, .length = 5u, .data = {1, 2, 3, 4, 5, 6, 7, 8}};
  uint32_t words[G4_FDCAN_RAM_FRAME_WORDS];
  /* Test */
  g4_fdcan_ram_pack_tx(&frame, words);
  /* Assert: standard id in 28:18, DLC in 19:16, nothing else; bytes past the length 0. */
  assert_int_equal(words[0], 0x72Au << 18);
  assert_int_equal(words[1], 5u << 16);
  assert_int_equal(words[2], 0x04030201u);
  assert_int_equal(words[3], 0x00000005u);
}

static void test_rx_element_round_trip_and_refusals(void **state) {
  (void)state;
  /* Fixture: a received element = the transmit layout plus a timestamp in 15:0. */
  const can_frame_t sent = {.id = 0x601u, .length = 8u, .data = {9, 8, 7, 6, 5, 4, 3, 2}};
  uint32_t words[G4_FDCAN_RAM_FRAME_WORDS];
  g4_fdcan_ram_pack_tx(&sent, words);
  words[1] |= 0xBEEFu;
  can_frame_t got;
  uint16_t stamp = 0u;
  /* Test */
  const bool ok = g4_fdcan_ram_unpack_rx(words, &got, &stamp);
  /* Assert */
  assert_true(ok);
  assert_int_equal(got.id, sent.id);
  assert_int_equal(got.length, sent.length);
  assert_memory_equal(got.data, sent.data, 8);
  assert_int_equal(stamp, 0xBEEFu);
  /* A classic DLC above 8 carries 8 bytes; extended, remote and FD frames are refused. */
  words[1] = 12u << 16;
  assert_true(g4_fdcan_ram_unpack_rx(words, &got, &stamp));
  assert_int_equal(got.length, 8u);
  const uint32_t refused_word0[] = {words[0] | (1u << 30), words[0] | (1u << 29)};
  for (size_t i = 0; i < 2; i++) {
    const uint32_t bad[G4_FDCAN_RAM_FRAME_WORDS] = {refused_word0[i], words[1], 0u, 0u};
    assert_false(g4_fdcan_ram_unpack_rx(bad, &got, &stamp));
  }
  const uint32_t fd[G4_FDCAN_RAM_FRAME_WORDS] = {words[0], words[1] | (1u << 21), 0u, 0u};
  assert_false(g4_fdcan_ram_unpack_rx(fd, &got, &stamp));
}

static void test_rx_time_subtracts_the_frames_age(void **state) {
  (void)state;
  /* Fixture, Test and Assert: age 60 us; the 16-bit stamp wrapped; the node timer wrapped. */
  assert_int_equal(g4_fdcan_ram_rx_time_us(1000000u, 100u, 40u), 999940u);
  assert_int_equal(g4_fdcan_ram_rx_time_us(1000000u, 10u, 65530u), 1000000u - 16u);
  assert_int_equal(g4_fdcan_ram_rx_time_us(5u, 300u, 290u), 0xFFFFFFFBu);
  assert_int_equal(g4_fdcan_ram_rx_time_us(777u, 1234u, 1234u), 777u);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_timing_of_the_board),
      cmocka_unit_test(test_timing_of_other_clocks),
      cmocka_unit_test(test_timing_refuses_what_cannot_be_met),
      cmocka_unit_test(test_tolerance_follows_iso_11898),
      cmocka_unit_test(test_ram_layout_is_rm0440s),
      cmocka_unit_test(test_filter_passes_sync_and_own_command),
      cmocka_unit_test(test_tx_element_packs_a_classic_frame),
      cmocka_unit_test(test_rx_element_round_trip_and_refusals),
      cmocka_unit_test(test_rx_time_subtracts_the_frames_age),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
