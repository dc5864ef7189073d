/* The LSM303DLHC magnetometer driver against a register-level fake of the chip. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "fake_lsm303dlhc_mag.h"
#include "lsm303dlhc_mag.h"

typedef struct {
  fake_lsm303dlhc_mag_t chip;
  bus_t bus;
  lsm303dlhc_mag_t mag;
} fixture_t;

static void fixture_init(fixture_t *const f, const lsm303dlhc_mag_settings_t *const settings) {
  fake_lsm303dlhc_mag_init(&f->chip, LSM303DLHC_MAG_ADDRESS);
  f->bus = fake_lsm303dlhc_mag_bus(&f->chip);
  lsm303dlhc_mag_init(&f->mag, &f->bus, LSM303DLHC_MAG_ADDRESS, settings);
}

static void probe_identifies_the_chip_and_refuses_another(void **state) {
  (void)state;
  fixture_t f;
  fixture_init(&f, &lsm303dlhc_mag_settings_default);

  const lsm303dlhc_mag_status_t genuine = lsm303dlhc_mag_probe(&f.mag);
  f.chip.registers[LSM303DLHC_MAG_REG_IRB] = 0x35u;
  const lsm303dlhc_mag_status_t other = lsm303dlhc_mag_probe(&f.mag);

  assert_int_equal(genuine, LSM303DLHC_MAG_OK);
  assert_int_equal(other, LSM303DLHC_MAG_WRONG_ID);
}

static void configure_writes_each_register_in_its_own_transfer(void **state) {
  (void)state;
  fixture_t f;
  const lsm303dlhc_mag_settings_t settings = {.odr = LSM303DLHC_MAG_ODR_75_HZ,
                                              .range = LSM303DLHC_MAG_RANGE_4_0_GAUSS};
  fixture_init(&f, &settings);

  const lsm303dlhc_mag_status_t status = lsm303dlhc_mag_configure(&f.mag);

  assert_int_equal(status, LSM303DLHC_MAG_OK);
  assert_int_equal(f.chip.protocol_errors, 0);
  assert_int_equal(f.chip.write_transfers, 3);
  assert_int_equal(f.chip.registers[LSM303DLHC_MAG_REG_CRA], 6u << 2);
  assert_int_equal(f.chip.registers[LSM303DLHC_MAG_REG_CRB], 4u << 5);
  assert_int_equal(f.chip.registers[LSM303DLHC_MAG_REG_MR], LSM303DLHC_MAG_MR_CONTINUOUS);
  assert_true(f.mag.configured);
}

static void counts_come_in_sensor_order_from_the_chips_x_z_y(void **state) {
  (void)state;
  fixture_t f;
  fixture_init(&f, &lsm303dlhc_mag_settings_default);
  fake_lsm303dlhc_mag_set_counts(&f.chip, 1000, -500, 0x123);
  int16_t counts[3] = {0, 0, 0};

  const lsm303dlhc_mag_status_t status = lsm303dlhc_mag_read_counts(&f.mag, counts);

  assert_int_equal(status, LSM303DLHC_MAG_OK);
  assert_int_equal(counts[0], 1000);
  assert_int_equal(counts[1], -500);
  assert_int_equal(counts[2], 0x123);
  assert_int_equal(f.chip.registers[LSM303DLHC_MAG_REG_OUT_X_H + 2u], 0x01u); /* Z_H */
  assert_int_equal(f.chip.registers[LSM303DLHC_MAG_REG_OUT_X_H + 3u], 0x23u); /* Z_L */
}

/* Every range: the field the fake sees (uT) comes back within one count. */
static void field_in_microtesla_matches_at_every_gain(void **state) {
  (void)state;
  const float field_ut[3] = {21.5f, -4.25f, -43.0f};
  for (int range = LSM303DLHC_MAG_RANGE_1_3_GAUSS; range <= LSM303DLHC_MAG_RANGE_8_1_GAUSS;
       range++) {
    fixture_t f;
    const lsm303dlhc_mag_settings_t settings = {.odr = LSM303DLHC_MAG_ODR_220_HZ,
                                                .range = (lsm303dlhc_mag_range_t)range};
    fixture_init(&f, &settings);
    assert_int_equal(lsm303dlhc_mag_configure(&f.mag), LSM303DLHC_MAG_OK);
    fake_lsm303dlhc_mag_set_field_ut(&f.chip, field_ut);
    float read_ut[3] = {0.0f, 0.0f, 0.0f};

    const lsm303dlhc_mag_status_t status = lsm303dlhc_mag_read_ut(&f.mag, read_ut);

    assert_int_equal(status, LSM303DLHC_MAG_OK);
    for (unsigned axis = 0u; axis < 3u; axis++) {
      const float count_ut = lsm303dlhc_mag_ut_per_count(settings.range, axis);
      assert_true(count_ut > 0.0f);
      assert_float_equal(read_ut[axis], field_ut[axis], 0.5f * count_ut + 1e-5f);
    }
  }
}

static void overflow_is_reported_and_the_next_sample_is_normal(void **state) {
  (void)state;
  fixture_t f;
  fixture_init(&f, &lsm303dlhc_mag_settings_default);
  const float beyond_ut[3] = {10.0f, 10.0f, 300.0f}; /* z beyond +-1.3 gauss */
  const float normal_ut[3] = {10.0f, 10.0f, 30.0f};
  float read_ut[3] = {-1.0f, -1.0f, -1.0f};

  fake_lsm303dlhc_mag_set_field_ut(&f.chip, beyond_ut);
  const lsm303dlhc_mag_status_t overflowed = lsm303dlhc_mag_read_ut(&f.mag, read_ut);
  const float untouched = read_ut[2];
  fake_lsm303dlhc_mag_set_field_ut(&f.chip, normal_ut);
  const lsm303dlhc_mag_status_t recovered = lsm303dlhc_mag_read_ut(&f.mag, read_ut);

  assert_int_equal(overflowed, LSM303DLHC_MAG_OVERFLOWED);
  assert_float_equal(untouched, -1.0f, 0.0f);
  assert_int_equal(recovered, LSM303DLHC_MAG_OK);
  assert_float_equal(read_ut[2], 30.0f, 0.1f);
}

/* The chip drops off the bus, comes back power-cycled (asleep, default gain): the
 * driver reports NACK, then configures it again on its own and reads the field. */
static void nack_is_reported_and_a_power_cycled_chip_recovers(void **state) {
  (void)state;
  fixture_t f;
  const lsm303dlhc_mag_settings_t settings = {.odr = LSM303DLHC_MAG_ODR_220_HZ,
                                              .range = LSM303DLHC_MAG_RANGE_2_5_GAUSS};
  fixture_init(&f, &settings);
  const float field_ut[3] = {-12.0f, 33.0f, 5.0f};
  float read_ut[3] = {0.0f, 0.0f, 0.0f};
  assert_int_equal(lsm303dlhc_mag_read_ut(&f.mag, read_ut), LSM303DLHC_MAG_OK);

  f.chip.present = false;
  const lsm303dlhc_mag_status_t absent = lsm303dlhc_mag_read_ut(&f.mag, read_ut);
  f.chip.present = true;
  fake_lsm303dlhc_mag_power_cycle(&f.chip);
  fake_lsm303dlhc_mag_set_field_ut(&f.chip, field_ut);
  const lsm303dlhc_mag_status_t back = lsm303dlhc_mag_read_ut(&f.mag, read_ut);

  assert_int_equal(absent, LSM303DLHC_MAG_NACK);
  assert_int_equal(f.mag.failures, 1);
  assert_int_equal(back, LSM303DLHC_MAG_OK);
  assert_int_equal(f.chip.registers[LSM303DLHC_MAG_REG_MR], LSM303DLHC_MAG_MR_CONTINUOUS);
  assert_int_equal(f.chip.registers[LSM303DLHC_MAG_REG_CRB], 3u << 5);
  for (unsigned axis = 0u; axis < 3u; axis++) {
    assert_float_equal(read_ut[axis], field_ut[axis], lsm303dlhc_mag_ut_per_count(settings.range, axis));
  }
}

static void a_chip_that_ignores_writes_is_refused(void **state) {
  (void)state;
  fixture_t f;
  fixture_init(&f, &lsm303dlhc_mag_settings_default);
  f.chip.ignore_writes = true;
  int16_t counts[3];

  const lsm303dlhc_mag_status_t status = lsm303dlhc_mag_read_counts(&f.mag, counts);

  assert_int_equal(status, LSM303DLHC_MAG_CONFIG_LOST);
  assert_false(f.mag.configured);
}

static void settings_outside_the_table_are_refused(void **state) {
  (void)state;
  fixture_t f;
  const lsm303dlhc_mag_settings_t settings = {.odr = LSM303DLHC_MAG_ODR_220_HZ,
                                              .range = (lsm303dlhc_mag_range_t)0};
  fake_lsm303dlhc_mag_init(&f.chip, LSM303DLHC_MAG_ADDRESS);
  f.bus = fake_lsm303dlhc_mag_bus(&f.chip);

  const lsm303dlhc_mag_status_t at_init =
      lsm303dlhc_mag_init(&f.mag, &f.bus, LSM303DLHC_MAG_ADDRESS, &settings);
  const lsm303dlhc_mag_status_t at_configure = lsm303dlhc_mag_configure(&f.mag);

  assert_int_equal(at_init, LSM303DLHC_MAG_BAD_SETTING);
  assert_int_equal(at_configure, LSM303DLHC_MAG_BAD_SETTING);
  assert_int_equal(f.chip.write_transfers, 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(probe_identifies_the_chip_and_refuses_another),
      cmocka_unit_test(configure_writes_each_register_in_its_own_transfer),
      cmocka_unit_test(counts_come_in_sensor_order_from_the_chips_x_z_y),
      cmocka_unit_test(field_in_microtesla_matches_at_every_gain),
      cmocka_unit_test(overflow_is_reported_and_the_next_sample_is_normal),
      cmocka_unit_test(nack_is_reported_and_a_power_cycled_chip_recovers),
      cmocka_unit_test(a_chip_that_ignores_writes_is_refused),
      cmocka_unit_test(settings_outside_the_table_are_refused),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
