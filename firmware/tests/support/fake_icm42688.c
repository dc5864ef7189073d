/* The fake ICM-42688-P's register side: reset values, banks, bus transfers (with their
 * time), register reads and writes, failure injection. */
#include "fake_icm42688.h"

#include <string.h>

#include "fake_icm42688_internal.h"
#include "icm42688_regs.h"

#define FAKE_ICM42688_BANK_MAX 4u
#define FAKE_ICM42688_READ_HEADER_BYTES 3u  /* address+W, register, address+R */
#define FAKE_ICM42688_WRITE_HEADER_BYTES 2u /* address+W, register */

static void fake_icm42688_reset_registers(fake_icm42688_t *const fake) {
  static const uint8_t bank0_defaults[][2] = {
      {0x13u, 0x05u}, /* DRIVE_CONFIG */
      {ICM42688_REG_INTF_CONFIG0, ICM42688_INTF_CONFIG0_RESET},
      {0x4Du, 0x91u},                      /* INTF_CONFIG1 */
      {ICM42688_REG_GYRO_CONFIG0, 0x06u},  /* 2000 deg/s, 1 kHz */
      {ICM42688_REG_ACCEL_CONFIG0, 0x06u}, /* 16 g, 1 kHz */
      {0x51u, 0x16u},
      {0x52u, 0x11u},
      {0x53u, 0x0Du},
      {ICM42688_REG_TMST_CONFIG, 0x23u},
      {ICM42688_REG_INT_CONFIG1, ICM42688_INT_CONFIG1_RESET},
      {ICM42688_REG_INT_SOURCE0, 0x10u}, /* RESET_DONE_INT1_EN */
  };
  memset(fake->registers, 0, sizeof(fake->registers));
  for (size_t i = 0; i < sizeof(bank0_defaults) / sizeof(bank0_defaults[0]); ++i) {
    fake->registers[0][bank0_defaults[i][0]] = bank0_defaults[i][1];
  }
  fake->bank = 0u;
  fake->int_status = ICM42688_INT_STATUS_RESET_DONE;
  fake->int1_high = false;
  fake->gyro_valid_ns = 0;
  fake_icm42688_fifo_flush(fake);
  fake_icm42688_schedule(fake); /* sensors off */
}

void fake_icm42688_init(fake_icm42688_t *const fake, uint8_t address) {
  memset(fake, 0, sizeof(*fake));
  fake->address = address;
  fake->who_am_i = ICM42688_WHO_AM_I_VALUE;
  fake->nack_after = -1;
  fake->temp_degc = 25.0f;
  fake->st_gyro_ratio = 1.0f;
  fake->st_accel_ratio = 1.0f;
  static const uint8_t gyro_codes[3] = {52u, 61u, 47u};
  static const uint8_t accel_codes[3] = {38u, 44u, 57u};
  fake_icm42688_set_trim_codes(fake, gyro_codes, accel_codes);
  fake_icm42688_reset_registers(fake);
}

void fake_icm42688_set_trim_codes(fake_icm42688_t *const fake, const uint8_t gyro[3],
                                  const uint8_t accel[3]) {
  memcpy(fake->trim_gyro, gyro, sizeof(fake->trim_gyro));
  memcpy(fake->trim_accel, accel, sizeof(fake->trim_accel));
}

void fake_icm42688_set_source(fake_icm42688_t *const fake, fake_icm42688_source_t source,
                              void *context) {
  fake->source = source;
  fake->source_context = context;
}

void fake_icm42688_set_int1(fake_icm42688_t *const fake, fake_icm42688_int1_t on_int1,
                            void *context) {
  fake->on_int1 = on_int1;
  fake->int1_context = context;
}

int64_t fake_icm42688_next_sample_ns(const fake_icm42688_t *const fake) {
  return fake->next_sample_ns;
}

uint32_t fake_icm42688_timer_us(const fake_icm42688_t *const fake) {
  return fake->timer_offset_us + (uint32_t)(uint64_t)(fake->now_ns / 1000);
}

void fake_icm42688_advance_us(fake_icm42688_t *const fake, uint32_t microseconds) {
  fake_icm42688_advance_to_ns(fake, fake->now_ns + (int64_t)microseconds * 1000);
}

/* --- register reads ------------------------------------------------------------- */

static uint8_t fake_icm42688_read_count(fake_icm42688_t *const fake, uint8_t reg) {
  if (reg == ICM42688_REG_FIFO_COUNTH || !fake->count_latched) {
    fake->count_latch = fake_icm42688_fifo_level(fake);
    fake->count_latched = true;
  }
  const bool big = (FAKE_ICM42688_B0(fake, ICM42688_REG_INTF_CONFIG0) &
                    ICM42688_INTF_CONFIG0_FIFO_COUNT_BIG) != 0u;
  const bool high = (reg == ICM42688_REG_FIFO_COUNTH) == big;
  return (uint8_t)(high ? fake->count_latch >> 8 : fake->count_latch & 0xFFu);
}

static uint8_t fake_icm42688_read_bank0(fake_icm42688_t *const fake, uint8_t reg) {
  if (reg >= ICM42688_REG_TEMP_DATA1 && reg < ICM42688_REG_TEMP_DATA1 + FAKE_ICM42688_DATA_BYTES) {
    uint8_t bytes[FAKE_ICM42688_DATA_BYTES];
    fake_icm42688_data_bytes(fake, bytes);
    return bytes[reg - ICM42688_REG_TEMP_DATA1];
  }
  switch (reg) {
    case ICM42688_REG_INT_STATUS: {
      const uint8_t status = fake->int_status;
      fake->int_status = 0u;
      fake->int1_high = false;
      return status;
    }
    case ICM42688_REG_FIFO_COUNTH:
    case ICM42688_REG_FIFO_COUNTL:
      return fake_icm42688_read_count(fake, reg);
    case ICM42688_REG_FIFO_DATA:
      return fake_icm42688_fifo_pop_byte(fake);
    case ICM42688_REG_FIFO_LOST_PKT0:
      return (uint8_t)(fake->lost_packets & 0xFFu);
    case ICM42688_REG_FIFO_LOST_PKT0 + 1u:
      return (uint8_t)(fake->lost_packets >> 8);
    case ICM42688_REG_WHO_AM_I:
      return fake->who_am_i;
    default:
      return fake->registers[0][reg];
  }
}

static uint8_t fake_icm42688_read_register(fake_icm42688_t *const fake, uint8_t reg) {
  if (reg == ICM42688_REG_BANK_SEL) return fake->bank;
  if (fake->bank == 0u) return fake_icm42688_read_bank0(fake, reg);
  if (fake->bank == 1u && reg >= ICM42688_REG_XG_ST_DATA && reg < ICM42688_REG_XG_ST_DATA + 3u) {
    return fake->trim_gyro[reg - ICM42688_REG_XG_ST_DATA];
  }
  if (fake->bank == 2u && reg >= ICM42688_REG_XA_ST_DATA && reg < ICM42688_REG_XA_ST_DATA + 3u) {
    return fake->trim_accel[reg - ICM42688_REG_XA_ST_DATA];
  }
  return fake->registers[fake->bank][reg];
}

/* --- register writes ------------------------------------------------------------ */

static void fake_icm42688_soft_reset(fake_icm42688_t *const fake) {
  fake->soft_resets++;
  fake_icm42688_reset_registers(fake);
  fake->busy_until_ns = fake->now_ns + FAKE_ICM42688_RESET_NS;
}

static void fake_icm42688_write_power(fake_icm42688_t *const fake, uint8_t value) {
  const uint8_t previous = FAKE_ICM42688_B0(fake, ICM42688_REG_PWR_MGMT0);
  FAKE_ICM42688_B0(fake, ICM42688_REG_PWR_MGMT0) = value;
  if (value == previous) return;
  fake->writes_blocked_until_ns = fake->now_ns + FAKE_ICM42688_POWER_WAIT_NS;
  const bool gyro_was_on = ((previous >> 2) & 0x03u) == 0x03u;
  const bool gyro_on = ((value >> 2) & 0x03u) == 0x03u;
  if (gyro_on && !gyro_was_on) fake->gyro_valid_ns = fake->now_ns + FAKE_ICM42688_GYRO_START_NS;
  if (fake_icm42688_sensors_on(value) != fake_icm42688_sensors_on(previous)) {
    fake_icm42688_schedule(fake);
  }
}

static void fake_icm42688_write_odr(fake_icm42688_t *const fake, uint8_t reg, uint8_t value) {
  const uint8_t previous = fake->registers[0][reg];
  fake->registers[0][reg] = value;
  const bool odr_changed = ((previous ^ value) & ICM42688_CONFIG0_ODR_MASK) != 0u;
  if (reg == ICM42688_REG_GYRO_CONFIG0 && odr_changed) {
    fake->odr_changed = true;
    fake_icm42688_schedule(fake);
  }
}

static bool fake_icm42688_read_only_bank0(uint8_t reg) {
  const bool data = reg >= ICM42688_REG_TEMP_DATA1 && reg <= ICM42688_REG_FIFO_DATA;
  return data || reg == ICM42688_REG_WHO_AM_I || reg == ICM42688_REG_FIFO_LOST_PKT0 ||
         reg == ICM42688_REG_FIFO_LOST_PKT0 + 1u;
}

static void fake_icm42688_write_bank0(fake_icm42688_t *const fake, uint8_t reg, uint8_t value) {
  if (fake_icm42688_read_only_bank0(reg)) {
    fake->protocol_errors++;
  } else if (reg == ICM42688_REG_DEVICE_CONFIG && (value & ICM42688_DEVICE_CONFIG_SOFT_RESET)) {
    fake_icm42688_soft_reset(fake);
  } else if (reg == ICM42688_REG_SIGNAL_PATH_RESET) { /* self-clearing bits */
    if ((value & ICM42688_SIGNAL_PATH_RESET_FIFO_FLUSH) != 0u) fake_icm42688_fifo_flush(fake);
  } else if (reg == ICM42688_REG_PWR_MGMT0) {
    fake_icm42688_write_power(fake, value);
  } else if (reg == ICM42688_REG_GYRO_CONFIG0 || reg == ICM42688_REG_ACCEL_CONFIG0) {
    fake_icm42688_write_odr(fake, reg, value);
  } else {
    fake->registers[0][reg] = value;
  }
}

static void fake_icm42688_write_register(fake_icm42688_t *const fake, uint8_t reg, uint8_t value) {
  if (reg == ICM42688_REG_BANK_SEL) {
    if (value > FAKE_ICM42688_BANK_MAX)
      fake->protocol_errors++;
    else
      fake->bank = value;
    return;
  }
  if (fake->now_ns < fake->writes_blocked_until_ns) {
    fake->timing_violations++; /* the chip ignores writes in this window */
    return;
  }
  const bool trim =
      (fake->bank == 1u && reg >= ICM42688_REG_XG_ST_DATA && reg < ICM42688_REG_XG_ST_DATA + 3u) ||
      (fake->bank == 2u && reg >= ICM42688_REG_XA_ST_DATA && reg < ICM42688_REG_XA_ST_DATA + 3u);
  if (fake->bank == 0u)
    fake_icm42688_write_bank0(fake, reg, value);
  else if (trim)
    fake->protocol_errors++; /* factory OTP */
  else
    fake->registers[fake->bank][reg] = value;
}

/* --- bus ------------------------------------------------------------------------ */

static bus_status_t fake_icm42688_begin(fake_icm42688_t *const fake, uint8_t device) {
  fake->transfers++;
  fake->count_latched = false;
  if (device != fake->address || fake->absent) return BUS_NACK;
  if (fake->nack_after == 0) {
    fake->nack_after = -1;
    return BUS_NACK;
  }
  if (fake->nack_after > 0) fake->nack_after--;
  if (fake->now_ns < fake->busy_until_ns) return BUS_NACK;
  return BUS_OK;
}

/* Lets the clock run to the end of byte `index` of a transfer started at `start_ns`. */
static void fake_icm42688_bus_time(fake_icm42688_t *const fake, int64_t start_ns, size_t index) {
  if (fake->bus_byte_ns == 0u) return;
  fake_icm42688_advance_to_ns(fake, start_ns + (int64_t)index * (int64_t)fake->bus_byte_ns);
}

static bus_status_t fake_icm42688_bus_read(void *context, uint8_t device, uint8_t reg,
                                           uint8_t *data, size_t length) {
  fake_icm42688_t *const fake = context;
  const bus_status_t status = fake_icm42688_begin(fake, device);
  if (status != BUS_OK) return status;
  const int64_t start_ns = fake->now_ns;
  uint8_t address = (uint8_t)(reg & 0x7Fu);
  for (size_t i = 0; i < length; ++i) {
    fake_icm42688_bus_time(fake, start_ns, FAKE_ICM42688_READ_HEADER_BYTES + i);
    data[i] = fake_icm42688_read_register(fake, address);
    const bool fifo = fake->bank == 0u && address == ICM42688_REG_FIFO_DATA;
    if (!fifo) address = (uint8_t)((address + 1u) & 0x7Fu);
  }
  fake_icm42688_bus_time(fake, start_ns, FAKE_ICM42688_READ_HEADER_BYTES + length + 1u);
  const bool resume = (FAKE_ICM42688_B0(fake, ICM42688_REG_FIFO_CONFIG1) & 0x40u) != 0u;
  if (!resume) fake->fifo_read_offset = 0u; /* a packet read in part is read again */
  return BUS_OK;
}

static bus_status_t fake_icm42688_bus_write(void *context, uint8_t device, uint8_t reg,
                                            const uint8_t *data, size_t length) {
  fake_icm42688_t *const fake = context;
  const bus_status_t status = fake_icm42688_begin(fake, device);
  if (status != BUS_OK) return status;
  const int64_t start_ns = fake->now_ns;
  uint8_t address = (uint8_t)(reg & 0x7Fu);
  for (size_t i = 0; i < length; ++i) {
    fake_icm42688_bus_time(fake, start_ns, FAKE_ICM42688_WRITE_HEADER_BYTES + i + 1u);
    fake_icm42688_write_register(fake, address, data[i]);
    address = (uint8_t)((address + 1u) & 0x7Fu);
  }
  return BUS_OK;
}

static void fake_icm42688_bus_delay(void *context, uint32_t microseconds) {
  fake_icm42688_advance_us(context, microseconds);
}

static uint32_t fake_icm42688_bus_now(void *context) { return fake_icm42688_timer_us(context); }

bus_t fake_icm42688_bus(fake_icm42688_t *const fake) {
  const bus_t bus = {.read = fake_icm42688_bus_read,
                     .write = fake_icm42688_bus_write,
                     .delay_us = fake_icm42688_bus_delay,
                     .now_us = fake_icm42688_bus_now,
                     .context = fake};
  return bus;
}
