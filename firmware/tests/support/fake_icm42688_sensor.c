/* The fake ICM-42688-P's sensor side: its oscillator and ODR ticks, sampling and
 * quantisation, self-test actuation, the FIFO, the watermark and INT1. */
#include <math.h>
#include <string.h>

#include "fake_icm42688_internal.h"
#include "icm42688_regs.h"

#define FAKE_ICM42688_GRAVITY_MPS2 9.80665f
#define FAKE_ICM42688_RAD_PER_DEG 0.017453292519943295f
#define FAKE_ICM42688_CLIP 32767.0f
#define FAKE_ICM42688_FIFO_TEMP_LSB_PER_DEGC 2.07f
#define FAKE_ICM42688_DATA_TEMP_LSB_PER_DEGC 132.48f

/* Nominal sample period of an ODR code, ns (0: reserved code, no samples). */
static int64_t fake_icm42688_nominal_period_ns(uint8_t code) {
  static const int64_t periods_ns[16] = {
      0,        31250,    62500,    125000,   250000,    500000,    1000000,   5000000,
      10000000, 20000000, 40000000, 80000000, 160000000, 320000000, 640000000, 2000000};
  return periods_ns[code & 0x0Fu];
}

static int64_t fake_icm42688_period_now_ns(const fake_icm42688_t *const fake) {
  return fake_icm42688_nominal_period_ns(FAKE_ICM42688_B0(fake, ICM42688_REG_GYRO_CONFIG0));
}

/* The next true period: nominal / (1 + ppm 1e-6), exact over time (rational remainder). */
static int64_t fake_icm42688_step_ns(fake_icm42688_t *const fake) {
  const int64_t numerator = fake_icm42688_period_now_ns(fake) * 1000000;
  const int64_t denominator = 1000000 + (int64_t)fake->clock_error_ppm;
  int64_t step = numerator / denominator;
  fake->period_remainder += numerator % denominator;
  if (fake->period_remainder >= denominator) {
    fake->period_remainder -= denominator;
    ++step;
  }
  return step;
}

bool fake_icm42688_sensors_on(uint8_t power) {
  const bool gyro_on = ((power >> 2) & 0x03u) == 0x03u;
  const bool accel_on = (power & 0x03u) >= 0x02u;
  return gyro_on || accel_on;
}

void fake_icm42688_schedule(fake_icm42688_t *const fake) {
  fake->period_remainder = 0;
  const bool on = fake_icm42688_sensors_on(FAKE_ICM42688_B0(fake, ICM42688_REG_PWR_MGMT0));
  const int64_t period_ns = fake_icm42688_period_now_ns(fake);
  fake->next_sample_ns = FAKE_ICM42688_NEVER;
  if (on && period_ns > 0) fake->next_sample_ns = fake->now_ns + fake_icm42688_step_ns(fake);
}

static void fake_icm42688_int1_event(fake_icm42688_t *const fake) {
  if ((FAKE_ICM42688_B0(fake, ICM42688_REG_INT_CONFIG1) & ICM42688_INT_CONFIG1_ASYNC_RESET) != 0u) {
    return;
  }
  const bool latched =
      (FAKE_ICM42688_B0(fake, ICM42688_REG_INT_CONFIG) & ICM42688_INT_CONFIG_INT1_LATCHED) != 0u;
  if (latched && fake->int1_high) return;
  fake->int1_high = latched;
  fake->int1_edges++;
  fake->int1_last_edge_ns = fake->now_ns;
  if (fake->on_int1 != NULL) fake->on_int1(fake->int1_context, fake->now_ns);
}

static void fake_icm42688_raise(fake_icm42688_t *const fake, uint8_t status, uint8_t source) {
  fake->int_status |= status;
  if ((FAKE_ICM42688_B0(fake, ICM42688_REG_INT_SOURCE0) & source) != 0u) {
    fake_icm42688_int1_event(fake);
  }
}

static int16_t fake_icm42688_quantise(float value, float lsb) {
  float counts = value / lsb;
  if (!(counts == counts)) counts = 0.0f; /* NaN */
  if (counts > FAKE_ICM42688_CLIP) counts = FAKE_ICM42688_CLIP;
  if (counts < -FAKE_ICM42688_CLIP) counts = -FAKE_ICM42688_CLIP;
  return (int16_t)lroundf(counts);
}

static int16_t fake_icm42688_saturate(float counts) {
  if (counts > FAKE_ICM42688_CLIP) return (int16_t)FAKE_ICM42688_CLIP;
  if (counts < -FAKE_ICM42688_CLIP) return (int16_t)-FAKE_ICM42688_CLIP;
  return (int16_t)lroundf(counts);
}

/* Factory self-test response of trim `code` at FS_SEL `fs_select`, LSB. */
static float fake_icm42688_trim_lsb(uint8_t code, unsigned fs_select) {
  const float at_lowest_range = 2620.0f * powf(1.01f, (float)code - 1.0f);
  return ldexpf(at_lowest_range, (int)fs_select - 3);
}

/* Adds the self-test actuation of the enabled axes to `raw`. */
static void fake_icm42688_actuate(const fake_icm42688_t *const fake, int16_t raw[6]) {
  const uint8_t enable = FAKE_ICM42688_B0(fake, ICM42688_REG_SELF_TEST_CONFIG);
  const unsigned acc_fs = FAKE_ICM42688_B0(fake, ICM42688_REG_ACCEL_CONFIG0) >> 5;
  const unsigned gyr_fs = FAKE_ICM42688_B0(fake, ICM42688_REG_GYRO_CONFIG0) >> 5;
  const bool accel_powered = (enable & ICM42688_SELF_TEST_ACCEL_POWER) != 0u;
  for (unsigned axis = 0; axis < 3u; ++axis) {
    if ((enable & (1u << axis)) != 0u) {
      const float shift =
          fake->st_gyro_ratio * fake_icm42688_trim_lsb(fake->trim_gyro[axis], gyr_fs);
      raw[3u + axis] = fake_icm42688_saturate((float)raw[3u + axis] + shift);
    }
    if (accel_powered && (enable & (8u << axis)) != 0u) {
      const float shift =
          fake->st_accel_ratio * fake_icm42688_trim_lsb(fake->trim_accel[axis], acc_fs);
      raw[axis] = fake_icm42688_saturate((float)raw[axis] + shift);
    }
  }
}

/* The source's motion at this tick, quantised at the current full scales. */
static void fake_icm42688_measure(fake_icm42688_t *const fake,
                                  fake_icm42688_record_t *const record) {
  static const float still_acc_mps2[3] = {0.0f, 0.0f, FAKE_ICM42688_GRAVITY_MPS2};
  memset(record->gyr_rads, 0, sizeof(record->gyr_rads));
  memcpy(record->acc_mps2, still_acc_mps2, sizeof(record->acc_mps2));
  if (fake->source != NULL) {
    fake->source(fake->source_context, record->sequence, record->time_ns, record->gyr_rads,
                 record->acc_mps2);
  }
  const unsigned acc_fs = (FAKE_ICM42688_B0(fake, ICM42688_REG_ACCEL_CONFIG0) >> 5) & 0x03u;
  const unsigned gyr_fs = FAKE_ICM42688_B0(fake, ICM42688_REG_GYRO_CONFIG0) >> 5;
  const float acc_lsb = (float)(16u >> acc_fs) * FAKE_ICM42688_GRAVITY_MPS2 / 32768.0f;
  const float gyr_lsb = ldexpf(2000.0f, -(int)gyr_fs) * FAKE_ICM42688_RAD_PER_DEG / 32768.0f;
  for (unsigned axis = 0; axis < 3u; ++axis) {
    fake->raw_measured[axis] = fake_icm42688_quantise(record->acc_mps2[axis], acc_lsb);
    fake->raw_measured[3u + axis] = fake_icm42688_quantise(record->gyr_rads[axis], gyr_lsb);
  }
}

void fake_icm42688_put16(const fake_icm42688_t *const fake, uint8_t *const bytes, uint16_t value) {
  const bool big =
      (FAKE_ICM42688_B0(fake, ICM42688_REG_INTF_CONFIG0) & ICM42688_INTF_CONFIG0_DATA_BIG) != 0u;
  bytes[big ? 0 : 1] = (uint8_t)(value >> 8);
  bytes[big ? 1 : 0] = (uint8_t)(value & 0xFFu);
}

void fake_icm42688_data_bytes(const fake_icm42688_t *const fake,
                              uint8_t bytes[FAKE_ICM42688_DATA_BYTES]) {
  const float temp = (fake->temp_degc - 25.0f) * FAKE_ICM42688_DATA_TEMP_LSB_PER_DEGC;
  fake_icm42688_put16(fake, bytes, (uint16_t)fake_icm42688_saturate(temp));
  for (unsigned i = 0; i < 6u; ++i) {
    fake_icm42688_put16(fake, &bytes[2u + 2u * i], (uint16_t)fake->raw[i]);
  }
}

static void fake_icm42688_build_packet(fake_icm42688_t *const fake, uint8_t *const packet) {
  packet[0] = (uint8_t)(ICM42688_FIFO_HEADER_PACKET3 | ICM42688_FIFO_HEADER_TMST_ODR |
                        (fake->odr_changed ? 0x03u : 0x00u));
  fake->odr_changed = false;
  for (unsigned i = 0; i < 6u; ++i) {
    fake_icm42688_put16(fake, &packet[1u + 2u * i], (uint16_t)fake->raw[i]);
  }
  float temp = (fake->temp_degc - 25.0f) * FAKE_ICM42688_FIFO_TEMP_LSB_PER_DEGC;
  temp = temp > 127.0f ? 127.0f : (temp < -128.0f ? -128.0f : temp);
  packet[13] = (uint8_t)(int8_t)lroundf(temp);
  fake_icm42688_put16(fake, &packet[14], (uint16_t)(fake->chip_time_us & 0xFFFFu));
}

uint16_t fake_icm42688_fifo_level(const fake_icm42688_t *const fake) {
  const bool packets = (FAKE_ICM42688_B0(fake, ICM42688_REG_INTF_CONFIG0) &
                        ICM42688_INTF_CONFIG0_FIFO_COUNT_REC) != 0u;
  if (packets) return (uint16_t)fake->fifo_count;
  return (uint16_t)(fake->fifo_count * FAKE_ICM42688_PACKET_BYTES - fake->fifo_read_offset);
}

static uint16_t fake_icm42688_watermark(const fake_icm42688_t *const fake) {
  return (uint16_t)(FAKE_ICM42688_B0(fake, ICM42688_REG_FIFO_CONFIG2) |
                    ((FAKE_ICM42688_B0(fake, ICM42688_REG_FIFO_CONFIG3) & 0x0Fu) << 8));
}

/* The watermark and full events of a packet just written, `before` the level before. */
static void fake_icm42688_fifo_events(fake_icm42688_t *const fake, uint16_t before) {
  const uint16_t watermark = fake_icm42688_watermark(fake);
  const uint16_t after = fake_icm42688_fifo_level(fake);
  const bool every_write =
      (FAKE_ICM42688_B0(fake, ICM42688_REG_FIFO_CONFIG1) & ICM42688_FIFO_CONFIG1_WM_GT_TH) != 0u;
  const bool crossed =
      every_write ? after >= watermark : (before < watermark && after >= watermark);
  if (watermark > 0u && crossed) {
    fake_icm42688_raise(fake, ICM42688_INT_STATUS_FIFO_THS, ICM42688_INT_SOURCE0_FIFO_THS_INT1);
  }
  if (fake->fifo_count == FAKE_ICM42688_FIFO_PACKETS) {
    fake_icm42688_raise(fake, ICM42688_INT_STATUS_FIFO_FULL, ICM42688_INT_SOURCE0_FIFO_FULL_INT1);
  }
}

static void fake_icm42688_fifo_push(fake_icm42688_t *const fake,
                                    const fake_icm42688_record_t *const record) {
  const uint16_t before = fake_icm42688_fifo_level(fake);
  if (fake->fifo_count == FAKE_ICM42688_FIFO_PACKETS) { /* full: the oldest is lost */
    fake->fifo_head = (fake->fifo_head + 1u) % FAKE_ICM42688_FIFO_PACKETS;
    fake->fifo_count--;
    fake->fifo_read_offset = 0u;
    if (fake->lost_packets < UINT16_MAX) fake->lost_packets++;
  }
  const uint32_t slot = (fake->fifo_head + fake->fifo_count) % FAKE_ICM42688_FIFO_PACKETS;
  fake_icm42688_build_packet(fake, fake->fifo[slot]);
  fake->fifo_records[slot] = *record;
  fake->fifo_count++;
  fake_icm42688_fifo_events(fake, before);
}

static bool fake_icm42688_fifo_enabled(const fake_icm42688_t *const fake) {
  const uint8_t both = ICM42688_FIFO_CONFIG1_ACCEL_EN | ICM42688_FIFO_CONFIG1_GYRO_EN;
  const uint8_t mode =
      FAKE_ICM42688_B0(fake, ICM42688_REG_FIFO_CONFIG) & ICM42688_FIFO_CONFIG_MODE_MASK;
  return mode == ICM42688_FIFO_CONFIG_STREAM &&
         (FAKE_ICM42688_B0(fake, ICM42688_REG_FIFO_CONFIG1) & both) == both;
}

/* One ODR tick at fake->now_ns. */
static void fake_icm42688_take_sample(fake_icm42688_t *const fake) {
  fake_icm42688_record_t record = fake->last_record;
  record.sequence = fake->sequence;
  record.time_ns = fake->now_ns;
  if (!fake->stuck || fake->sequence == 0u) fake_icm42688_measure(fake, &record);
  fake->last_record = record;
  memcpy(fake->raw, fake->raw_measured, sizeof(fake->raw));
  fake_icm42688_actuate(fake, fake->raw);
  if (fake->now_ns < fake->gyro_valid_ns) {
    for (unsigned axis = 3u; axis < 6u; ++axis) fake->raw[axis] = ICM42688_RAW_INVALID;
  }
  fake_icm42688_raise(fake, ICM42688_INT_STATUS_DATA_RDY, ICM42688_INT_SOURCE0_UI_DRDY_INT1);
  if (fake_icm42688_fifo_enabled(fake)) fake_icm42688_fifo_push(fake, &record);
  fake->chip_time_us += (uint32_t)(fake_icm42688_period_now_ns(fake) / 1000);
  fake->sequence++;
}

void fake_icm42688_advance_to_ns(fake_icm42688_t *const fake, int64_t time_ns) {
  while (fake->next_sample_ns <= time_ns) {
    fake->now_ns = fake->next_sample_ns;
    fake_icm42688_take_sample(fake);
    fake->next_sample_ns += fake_icm42688_step_ns(fake);
  }
  if (time_ns > fake->now_ns) fake->now_ns = time_ns;
}

void fake_icm42688_fifo_flush(fake_icm42688_t *const fake) {
  fake->fifo_head = 0u;
  fake->fifo_count = 0u;
  fake->fifo_read_offset = 0u;
  fake->lost_packets = 0u;
}

static void fake_icm42688_log(fake_icm42688_t *const fake,
                              const fake_icm42688_record_t *const record) {
  if (fake->log_count == FAKE_ICM42688_LOG_SIZE) {
    fake->log_head = (fake->log_head + 1u) % FAKE_ICM42688_LOG_SIZE;
    fake->log_count--;
    fake->log_dropped++;
  }
  fake->log[(fake->log_head + fake->log_count) % FAKE_ICM42688_LOG_SIZE] = *record;
  fake->log_count++;
}

uint8_t fake_icm42688_fifo_pop_byte(fake_icm42688_t *const fake) {
  if (fake->fifo_count == 0u) return 0xFFu;
  const uint8_t byte = fake->fifo[fake->fifo_head][fake->fifo_read_offset++];
  if (fake->fifo_read_offset == FAKE_ICM42688_PACKET_BYTES) {
    fake_icm42688_log(fake, &fake->fifo_records[fake->fifo_head]);
    fake->fifo_head = (fake->fifo_head + 1u) % FAKE_ICM42688_FIFO_PACKETS;
    fake->fifo_count--;
    fake->fifo_read_offset = 0u;
  }
  return byte;
}

bool fake_icm42688_take_record(fake_icm42688_t *const fake, fake_icm42688_record_t *const record) {
  if (fake->log_count == 0u) return false;
  *record = fake->log[fake->log_head];
  fake->log_head = (fake->log_head + 1u) % FAKE_ICM42688_LOG_SIZE;
  fake->log_count--;
  return true;
}
