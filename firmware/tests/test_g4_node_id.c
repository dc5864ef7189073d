/* The production board's node id (boards/stm32g431kb/g4_node_id.c) on the host: the
 * provisioning record in the last flash page, and the fallback from the unique id. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "../boards/stm32g431kb/g4_node_id.c"

static const uint32_t uid_a[G4_NODE_ID_UID_WORDS] = {0x00530041u, 0x4E4B5015u, 0x20363641u};

static void test_valid_record_gives_its_id(void **state) {
  (void)state;
  /* Fixture */
  const uint32_t record[G4_NODE_ID_RECORD_WORDS] = {G4_NODE_ID_MAGIC, 42u, ~42u};
  /* Test */
  const g4_node_id_t id = g4_node_id_resolve(record, uid_a);
  /* Assert */
  assert_true(id.provisioned);
  assert_int_equal(id.node_id, 42u);
}

static void test_invalid_records_fall_back_to_the_unique_id(void **state) {
  (void)state;
  /* Fixture: erased flash, a wrong magic, a broken complement, ids 0 and 64. */
  const uint32_t records[][G4_NODE_ID_RECORD_WORDS] = {
      {0xFFFFFFFFu, 0xFFFFFFFFu, 0xFFFFFFFFu}, {G4_NODE_ID_MAGIC + 1u, 5u, ~5u},
      {G4_NODE_ID_MAGIC, 5u, ~6u}, {G4_NODE_ID_MAGIC, 0u, ~0u}, {G4_NODE_ID_MAGIC, 64u, ~64u}};
  const g4_node_id_t first = g4_node_id_resolve(records[0], uid_a);
  for (size_t i = 0; i < sizeof records / sizeof records[0]; i++) {
    /* Test */
    const g4_node_id_t id = g4_node_id_resolve(records[i], uid_a);
    /* Assert: not provisioned, in range, the same id for the same chip every time. */
    assert_false(id.provisioned);
    assert_in_range(id.node_id, G4_NODE_ID_MIN, G4_NODE_ID_MAX);
    assert_int_equal(id.node_id, first.node_id);
  }
}

static void test_unique_ids_spread_over_the_range(void **state) {
  (void)state;
  /* Fixture: 630 chips of one wafer lot (unique ids differ in their x/y coordinates). */
  const uint32_t erased[G4_NODE_ID_RECORD_WORDS] = {0xFFFFFFFFu, 0xFFFFFFFFu, 0xFFFFFFFFu};
  unsigned counts[G4_NODE_ID_MAX + 1u] = {0};
  for (uint32_t chip = 0u; chip < 630u; chip++) {
    const uint32_t uid[G4_NODE_ID_UID_WORDS] = {((chip % 30u) << 16) | (chip / 30u), uid_a[1], uid_a[2]};
    /* Test */
    counts[g4_node_id_resolve(erased, uid).node_id]++;
  }
  /* Assert: id 0 never; every id used; none more than 4x its share of 10. */
  assert_int_equal(counts[0], 0u);
  for (unsigned id = G4_NODE_ID_MIN; id <= G4_NODE_ID_MAX; id++) {
    assert_in_range(counts[id], 1u, 40u);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_valid_record_gives_its_id),
      cmocka_unit_test(test_invalid_records_fall_back_to_the_unique_id),
      cmocka_unit_test(test_unique_ids_spread_over_the_range),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
