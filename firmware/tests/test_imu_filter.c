/* The orientation filter (core/imu_filter.h) on simulated sensors whose true orientation
 * is known: a sensor at orientation q (sensor -> ENU) at rest measures acc = R(q)^T g_up,
 * mag = R(q)^T field, gyr = its body rate (+ bias + noise). */
#include <math.h>
#include <stdint.h>

/* cmocka needs these first */
// clang-format off
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>
// clang-format on

#include "imu_filter.h"
#include "imu_filter_math.h"

#define RATE_HZ 400.0f
#define PERIOD_S (1.0f / RATE_HZ)
#define DEG (3.14159265f / 180.0f)
#define GRAVITY_MPS2 9.81f

static const float field_enu_ut[3] = {0.0f, 20.0f, -42.0f}; /* north, dipping 64 degrees */

typedef struct {
  float q[4];         /* true orientation, sensor -> ENU */
  float body_rate[3]; /* rad/s, true angular velocity, sensor frame */
  float gyr_bias[3];  /* rad/s */
  float field_ut[3];  /* ENU field the magnetometer sees */
  float noise;        /* scale of the sensor noise (0: none) */
  uint32_t seed;      /* of the noise */
} sensor_t;

static float noise(sensor_t *const s) {
  s->seed = s->seed * 1664525u + 1013904223u;
  return ((float)(s->seed >> 8) / 16777216.0f - 0.5f) * 2.0f * s->noise;
}

static void sensor_init(sensor_t *const s, float angle_rad, const float axis[3]) {
  *s = (sensor_t){.q = {cosf(0.5f * angle_rad), 0.0f, 0.0f, 0.0f}, .seed = 1u};
  const float n = sqrtf(imu_filter_dot3(axis, axis));
  for (int i = 0; i < 3; ++i) {
    s->q[i + 1] = sinf(0.5f * angle_rad) * axis[i] / n;
    s->field_ut[i] = field_enu_ut[i];
  }
}

/* Advances the truth one period and returns what the sensor measures. */
static void sensor_step(sensor_t *const s, float gyr[3], float acc[3], float mag[3]) {
  const float half = 0.5f * PERIOD_S;
  const float w[3] = {s->body_rate[0], s->body_rate[1], s->body_rate[2]};
  const float angle = sqrtf(imu_filter_dot3(w, w)) * half;
  const float k = angle > 0.0f ? sinf(angle) / (angle / half) : half;
  const float step[4] = {cosf(angle), k * w[0], k * w[1], k * w[2]};
  float q[4];
  imu_filter_quat_multiply(s->q, step, q);
  const float conj[4] = {q[0], -q[1], -q[2], -q[3]};
  const float up[3] = {0.0f, 0.0f, GRAVITY_MPS2};
  imu_filter_quat_rotate(conj, up, acc);
  imu_filter_quat_rotate(conj, s->field_ut, mag);
  for (int i = 0; i < 4; ++i) s->q[i] = q[i];
  for (int i = 0; i < 3; ++i) {
    gyr[i] = w[i] + s->gyr_bias[i] + 0.01f * noise(s);
    acc[i] += 0.05f * noise(s);
    mag[i] += 0.5f * noise(s);
  }
}

/* Runs `seconds` of the simulation through the filter (mag NULL when !use_mag). */
static void run(imu_filter_t *const f, sensor_t *const s, float seconds, bool use_mag) {
  const int samples = (int)(seconds * RATE_HZ + 0.5f);
  for (int i = 0; i < samples; ++i) {
    float gyr[3], acc[3], mag[3];
    sensor_step(s, gyr, acc, mag);
    imu_filter_update(f, gyr, acc, use_mag ? mag : NULL);
  }
}

/* Angles (rad) of the error rotation q_est ⊗ q_true^-1: total, heading, inclination. */
typedef struct {
  float total, heading, inclination;
} error_t;

static error_t orientation_error(const float q_est[4], const float q_true[4]) {
  const float conj[4] = {q_true[0], -q_true[1], -q_true[2], -q_true[3]};
  float e[4];
  imu_filter_quat_multiply(q_est, conj, e);
  const float w = fabsf(e[0]);
  return (error_t){.total = 2.0f * acosf(fminf(w, 1.0f)),
                   .heading = 2.0f * atanf(fabsf(e[3]) / fmaxf(w, 1e-9f)),
                   .inclination = 2.0f * acosf(fminf(sqrtf(e[0] * e[0] + e[3] * e[3]), 1.0f))};
}

static error_t filter_error(const imu_filter_t *const f, const sensor_t *const s) {
  float q[4];
  imu_filter_quaternion(f, q);
  return orientation_error(q, s->q);
}

static const float axis_tilted[3] = {1.0f, -2.0f, 0.5f};
static const float axis_up[3] = {0.0f, 0.0f, 1.0f};

static void test_still_sensor_converges_to_its_tilt_and_heading(void **state) {
  (void)state;
  /* Fixture: a sensor turned 70 degrees about a skew axis, still, noisy. */
  imu_filter_t f;
  sensor_t s;
  imu_filter_init(&f, &imu_filter_settings_default, PERIOD_S);
  sensor_init(&s, 70.0f * DEG, axis_tilted);
  s.noise = 1.0f;
  /* Test */
  run(&f, &s, 12.0f, true);
  /* Assert: within 0.3 degrees, the ENU frame's axes where the test put them. */
  const error_t e = filter_error(&f, &s);
  assert_true(e.inclination < 0.3f * DEG);
  assert_true(e.heading < 0.3f * DEG);
}

static void test_6d_heading_comes_from_the_gyroscope_only(void **state) {
  (void)state;
  /* Fixture: a level sensor turning about up at 1 rad/s; the field would point elsewhere. */
  imu_filter_t f;
  sensor_t s;
  imu_filter_init(&f, &imu_filter_settings_default, PERIOD_S);
  sensor_init(&s, 0.0f, axis_up);
  s.body_rate[2] = 1.0f;
  /* Test: 2 s in 6D (mag NULL), from a start heading of 0. */
  run(&f, &s, 2.0f, false);
  /* Assert: the output turned 2 rad about up, as the truth did (within 0.2 degrees). */
  const error_t e = filter_error(&f, &s);
  assert_true(e.total < 0.2f * DEG);
  assert_false(imu_filter_mag_disturbed(&f));
}

static void test_constant_rate_integrates_to_the_right_angle(void **state) {
  (void)state;
  /* Fixture: settled at rest, tilted, no noise. */
  imu_filter_t f;
  sensor_t s;
  imu_filter_init(&f, &imu_filter_settings_default, PERIOD_S);
  sensor_init(&s, 30.0f * DEG, axis_tilted);
  run(&f, &s, 4.0f, false);
  float before[4];
  imu_filter_quaternion(&f, before);
  /* Test: 0.5 s at 3 rad/s about the sensor's x axis (the low-pass barely corrects). */
  s.body_rate[0] = 3.0f;
  run(&f, &s, 0.5f, false);
  /* Assert: the filter turned by 1.5 rad relative to where it was, within 0.5 degrees. */
  float after[4];
  imu_filter_quaternion(&f, after);
  const float conj[4] = {before[0], -before[1], -before[2], -before[3]};
  float turn[4];
  imu_filter_quat_multiply(conj, after, turn); /* sensor-frame rotation */
  const float angle =
      2.0f *
      atan2f(sqrtf(turn[1] * turn[1] + turn[2] * turn[2] + turn[3] * turn[3]), fabsf(turn[0]));
  assert_float_equal(angle, 1.5f, 0.5f * DEG);
  assert_true(fabsf(turn[1]) > 0.999f * sinf(0.75f)); /* about x */
}

static void test_gyro_bias_is_estimated_at_rest(void **state) {
  (void)state;
  /* Fixture: a still, noisy sensor whose gyroscope reads (0.6, -1.1, 0.4) deg/s. */
  imu_filter_t f;
  sensor_t s;
  imu_filter_init(&f, &imu_filter_settings_default, PERIOD_S);
  sensor_init(&s, 20.0f * DEG, axis_tilted);
  s.noise = 1.0f;
  const float bias[3] = {0.6f * DEG, -1.1f * DEG, 0.4f * DEG};
  for (int i = 0; i < 3; ++i) s.gyr_bias[i] = bias[i];
  /* Test */
  run(&f, &s, 20.0f, false);
  /* Assert: at rest, every axis within 0.02 deg/s. */
  assert_true(imu_filter_at_rest(&f));
  float estimate[3];
  imu_filter_gyro_bias(&f, estimate);
  for (int i = 0; i < 3; ++i) assert_float_equal(estimate[i], bias[i], 0.02f * DEG);
}

static void test_gyro_bias_is_estimated_during_motion(void **state) {
  (void)state;
  /* Fixture: a level sensor spinning about up at 0.5 rad/s, its x/y gyroscope biased. */
  imu_filter_t f;
  sensor_t s;
  imu_filter_init(&f, &imu_filter_settings_default, PERIOD_S);
  sensor_init(&s, 0.0f, axis_up);
  s.body_rate[2] = 0.5f;
  s.noise = 1.0f;
  s.gyr_bias[0] = 0.8f * DEG;
  s.gyr_bias[1] = -0.5f * DEG;
  /* Test: never at rest, 120 s. */
  run(&f, &s, 120.0f, false);
  /* Assert: the horizontal bias within 0.1 deg/s, and the tilt held within 0.2 degrees. */
  assert_false(imu_filter_at_rest(&f));
  float estimate[3];
  imu_filter_gyro_bias(&f, estimate);
  assert_float_equal(estimate[0], s.gyr_bias[0], 0.1f * DEG);
  assert_float_equal(estimate[1], s.gyr_bias[1], 0.1f * DEG);
  assert_true(filter_error(&f, &s).inclination < 0.2f * DEG);
}

/* Settles 9D with the field learned: still 5 s, then 10 s turning about up at 40 deg/s. */
static void settle_9d(imu_filter_t *const f, sensor_t *const s) {
  imu_filter_init(f, &imu_filter_settings_default, PERIOD_S);
  sensor_init(s, 15.0f * DEG, axis_tilted);
  s->noise = 1.0f;
  run(f, s, 5.0f, true);
  s->body_rate[2] = 40.0f * DEG;
  run(f, s, 10.0f, true);
  s->body_rate[2] = 0.0f;
  run(f, s, 2.0f, true);
}

static void test_9d_holds_heading_in_a_disturbed_field(void **state) {
  (void)state;
  /* Fixture: settled 9D, field learned. */
  imu_filter_t f;
  sensor_t s;
  settle_9d(&f, &s);
  assert_false(imu_filter_mag_disturbed(&f));
  const float heading_before = filter_error(&f, &s).heading;
  /* Test: a magnet: the field 40 % stronger and turned 60 degrees about up, for 20 s. */
  s.field_ut[0] = 28.0f * sinf(60.0f * DEG);
  s.field_ut[1] = 28.0f * cosf(60.0f * DEG);
  s.field_ut[2] = -42.0f * 1.4f;
  run(&f, &s, 20.0f, true);
  /* Assert: heading held on the gyroscope (within 0.5 degrees of before), flagged. */
  assert_true(imu_filter_mag_disturbed(&f));
  assert_true(filter_error(&f, &s).heading < heading_before + 0.5f * DEG);
}

static void test_9d_clean_field_corrects_gyroscope_drift(void **state) {
  (void)state;
  /* Fixture: settled 9D; then the gyroscope gains a bias about up of 0.5 deg/s, which the
   * accelerometer cannot see, while the sensor turns slowly about up (so never at rest,
   * where the bias would be measured). A 6D filter on the same samples drifts with it. */
  imu_filter_t f;
  imu_filter_t f6;
  sensor_t s;
  settle_9d(&f, &s);
  f6 = f;
  sensor_t s6 = s;
  s.gyr_bias[2] = s6.gyr_bias[2] = 0.5f * DEG;
  s.body_rate[2] = s6.body_rate[2] = 10.0f * DEG;
  /* Test: 60 s. */
  run(&f, &s, 60.0f, true);
  const float heading_6d_before = filter_error(&f6, &s6).heading;
  run(&f6, &s6, 60.0f, false);
  /* Assert: 9D stays within the first-order correction's steady lag (drift rate times the
   * heading time constant, 4.5 degrees) plus 1 degree; 6D drifted by over 20 degrees. */
  const float lag = 0.5f * DEG * imu_filter_settings_default.mag_time_constant_s;
  assert_false(imu_filter_mag_disturbed(&f));
  assert_true(filter_error(&f, &s).heading < lag + 1.0f * DEG);
  assert_true(filter_error(&f6, &s6).heading > heading_6d_before + 20.0f * DEG);
}

static void test_9d_with_a_slower_magnetometer_finds_north(void **state) {
  (void)state;
  /* Fixture: a still sensor turned 150 degrees about up (so the heading has far to go), its
   * magnetometer read on one IMU sample in 8 (NULL in between, as a node passes it). */
  imu_filter_t f;
  sensor_t s;
  imu_filter_init(&f, &imu_filter_settings_default, PERIOD_S);
  sensor_init(&s, 150.0f * DEG, axis_up);
  s.noise = 1.0f;
  /* Test: 10 s. */
  for (int i = 0; i < (int)(10.0f * RATE_HZ); ++i) {
    float gyr[3], acc[3], mag[3];
    sensor_step(&s, gyr, acc, mag);
    imu_filter_update(&f, gyr, acc, i % 8 == 0 ? mag : NULL);
  }
  /* Assert: settled, heading within 0.5 degrees. */
  assert_true(imu_filter_settled(&f));
  assert_true(filter_error(&f, &s).heading < 0.5f * DEG);
}

static void test_bad_input_does_not_poison_the_state(void **state) {
  (void)state;
  /* Fixture: settled 9D. */
  imu_filter_t f;
  sensor_t s;
  settle_9d(&f, &s);
  const uint32_t rejected_before = imu_filter_rejected(&f);
  /* Test: NaN, inf and absurd vectors, each in one of the three inputs. */
  const float nan3[3] = {NAN, 0.0f, 0.0f};
  const float inf3[3] = {0.0f, INFINITY, 0.0f};
  const float huge3[3] = {0.0f, 0.0f, 1.0e30f};
  const float *const bad[3] = {nan3, inf3, huge3};
  for (int i = 0; i < 3; ++i) {
    float gyr[3], acc[3], mag[3];
    sensor_step(&s, gyr, acc, mag);
    imu_filter_update(&f, bad[i], acc, mag);
    imu_filter_update(&f, gyr, bad[i], mag);
    imu_filter_update(&f, gyr, acc, bad[i]);
  }
  run(&f, &s, 1.0f, true);
  /* Assert: 9 vectors counted, the state finite, the orientation still right. */
  assert_int_equal(imu_filter_rejected(&f) - rejected_before, 9);
  float q[4];
  imu_filter_quaternion(&f, q);
  for (int i = 0; i < 4; ++i) assert_true(isfinite(q[i]));
  float bias[3];
  imu_filter_gyro_bias(&f, bias);
  for (int i = 0; i < 3; ++i) assert_true(isfinite(bias[i]));
  assert_true(filter_error(&f, &s).total < 0.5f * DEG);
}

static void test_settled_after_the_initial_alignment(void **state) {
  (void)state;
  /* Fixture */
  imu_filter_t f6;
  imu_filter_t f9;
  sensor_t s6;
  sensor_t s9;
  imu_filter_init(&f6, &imu_filter_settings_default, PERIOD_S);
  imu_filter_init(&f9, &imu_filter_settings_default, PERIOD_S);
  sensor_init(&s6, 40.0f * DEG, axis_tilted);
  s9 = s6;
  const float alignment_s = imu_filter_settings_default.acc_time_constant_s;
  /* Test / Assert: not settled just before the accelerometer's time constant, settled
   * after; 9D the same with the magnetometer's data. */
  run(&f6, &s6, alignment_s - 0.1f, false);
  run(&f9, &s9, alignment_s - 0.1f, true);
  assert_false(imu_filter_settled(&f6));
  assert_false(imu_filter_settled(&f9));
  run(&f6, &s6, 0.2f, false);
  run(&f9, &s9, 0.2f, true);
  assert_true(imu_filter_settled(&f6));
  assert_true(imu_filter_settled(&f9));
}

static void test_invalid_settings_refuse_every_sample(void **state) {
  (void)state;
  /* Fixture: a period of 0 and a negative time constant. */
  imu_filter_settings_t negative = imu_filter_settings_default;
  negative.acc_time_constant_s = -1.0f;
  imu_filter_t f;
  imu_filter_init(&f, &imu_filter_settings_default, 0.0f);
  /* Test */
  const float gyr[3] = {1.0f, 0.0f, 0.0f};
  const float acc[3] = {0.0f, 0.0f, GRAVITY_MPS2};
  imu_filter_update(&f, gyr, acc, NULL);
  /* Assert: refused, counted, identity output, never settled. */
  assert_false(imu_filter_settings_valid(&imu_filter_settings_default, 0.0f));
  assert_false(imu_filter_settings_valid(&negative, PERIOD_S));
  assert_true(imu_filter_settings_valid(&imu_filter_settings_default, PERIOD_S));
  assert_int_equal(imu_filter_rejected(&f), 1);
  float q[4];
  imu_filter_quaternion(&f, q);
  assert_float_equal(q[0], 1.0f, 0.0f);
  assert_false(imu_filter_settled(&f));
}

static void test_own_trigonometry_matches_libm(void **state) {
  (void)state;
  /* Fixture / Test: atan2 on a grid of directions, sincos over [-pi/2, pi/2]. */
  float atan2_error = 0.0f;
  float sincos_error = 0.0f;
  for (int i = 0; i < 3600; ++i) {
    const float a = (float)i * 0.1f * DEG - 3.1f;
    const float y = sinf(a) * 3.0f;
    const float x = cosf(a) * 3.0f;
    atan2_error = fmaxf(atan2_error, fabsf(imu_filter_atan2(y, x) - atan2f(y, x)));
    float s;
    float c;
    imu_filter_sincos(0.5f * a, &s, &c);
    sincos_error = fmaxf(sincos_error, fmaxf(fabsf(s - sinf(0.5f * a)), fabsf(c - cosf(0.5f * a))));
  }
  /* Assert */
  assert_true(atan2_error < 5e-7f);
  assert_true(sincos_error < 3e-7f);
  assert_float_equal(imu_filter_atan2(0.0f, 0.0f), 0.0f, 0.0f);
  assert_float_equal(imu_filter_gain(0.01f, 1.0f), 1.0f - expf(-0.01f), 1e-7f);
  assert_float_equal(imu_filter_gain(2.0f, 1.0f), 1.0f - expf(-2.0f), 1e-6f);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_still_sensor_converges_to_its_tilt_and_heading),
      cmocka_unit_test(test_6d_heading_comes_from_the_gyroscope_only),
      cmocka_unit_test(test_constant_rate_integrates_to_the_right_angle),
      cmocka_unit_test(test_gyro_bias_is_estimated_at_rest),
      cmocka_unit_test(test_gyro_bias_is_estimated_during_motion),
      cmocka_unit_test(test_9d_holds_heading_in_a_disturbed_field),
      cmocka_unit_test(test_9d_clean_field_corrects_gyroscope_drift),
      cmocka_unit_test(test_9d_with_a_slower_magnetometer_finds_north),
      cmocka_unit_test(test_bad_input_does_not_poison_the_state),
      cmocka_unit_test(test_settled_after_the_initial_alignment),
      cmocka_unit_test(test_invalid_settings_refuse_every_sample),
      cmocka_unit_test(test_own_trigonometry_matches_libm),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
