/* A register-level fake of the LSM303DLHC's magnetometer (fake_lsm303dlhc_mag.h). */
#include "fake_lsm303dlhc_mag.h"

#define REG_CRA 0x00u
#define REG_CRB 0x01u
#define REG_MR 0x02u
#define REG_OUT_X_H 0x03u
#define REG_OUT_Y_L 0x08u
#define REG_SR 0x09u
#define REG_IRA 0x0Au
#define REG_IRC 0x0Cu
#define OVERFLOW_COUNTS (-4096)
#define COUNTS_MIN (-2048)
#define COUNTS_MAX 2047

static const uint8_t power_on_registers[FAKE_LSM303DLHC_MAG_REGISTERS] = {
    0x10u, 0x20u, 0x03u,                      /* CRA 15 Hz, CRB +-1.3 gauss, MR sleep */
    0u,    0u,    0u,    0u, 0u, 0u,          /* OUT_X_H .. OUT_Y_L */
    0x01u,                                    /* SR: data ready */
    0x48u, 0x34u, 0x33u,                      /* IRA IRB IRC: 'H' '4' '3' */
};

/* LSB/gauss per CRB gain code (the datasheet's table; code 0 answers as code 1). */
static const uint16_t gain_xy[8] = {1100u, 1100u, 855u, 670u, 450u, 400u, 330u, 230u};
static const uint16_t gain_z[8] = {980u, 980u, 760u, 600u, 400u, 355u, 295u, 205u};

void fake_lsm303dlhc_mag_power_cycle(fake_lsm303dlhc_mag_t *const fake) {
  for (uint8_t i = 0u; i < FAKE_LSM303DLHC_MAG_REGISTERS; i++) {
    fake->registers[i] = power_on_registers[i];
  }
  fake->pointer = 0u;
}

void fake_lsm303dlhc_mag_init(fake_lsm303dlhc_mag_t *const fake, uint8_t address) {
  *fake = (fake_lsm303dlhc_mag_t){.address = address, .present = true};
  fake_lsm303dlhc_mag_power_cycle(fake);
}

void fake_lsm303dlhc_mag_set_counts(fake_lsm303dlhc_mag_t *const fake, int16_t x, int16_t y,
                                    int16_t z) {
  fake->field_counts[0] = x;
  fake->field_counts[1] = y;
  fake->field_counts[2] = z;
  fake->field_in_counts = true;
}

static int16_t counts_of(float field_ut, uint16_t lsb_per_gauss) {
  const float counts = field_ut * (float)lsb_per_gauss / 100.0f;
  const float rounded = counts + (counts >= 0.0f ? 0.5f : -0.5f);
  if (rounded <= (float)COUNTS_MIN - 1.0f || rounded >= (float)COUNTS_MAX + 1.0f) {
    return OVERFLOW_COUNTS;
  }
  return (int16_t)rounded;
}

void fake_lsm303dlhc_mag_set_field_ut(fake_lsm303dlhc_mag_t *const fake,
                                      const float field_ut[3]) {
  for (unsigned axis = 0u; axis < 3u; axis++) {
    fake->field_ut[axis] = field_ut[axis];
  }
  fake->field_in_counts = false;
}

/* The counts of the field on each axis at the gain in CRB, x y z. */
static void field_counts(const fake_lsm303dlhc_mag_t *const fake, int16_t counts[3]) {
  if (fake->field_in_counts) {
    for (unsigned axis = 0u; axis < 3u; axis++) {
      counts[axis] = fake->field_counts[axis];
    }
    return;
  }
  const unsigned gain = (unsigned)fake->registers[REG_CRB] >> 5;
  counts[0] = counts_of(fake->field_ut[0], gain_xy[gain]);
  counts[1] = counts_of(fake->field_ut[1], gain_xy[gain]);
  counts[2] = counts_of(fake->field_ut[2], gain_z[gain]);
}

/* At the start of a read transfer the chip latches its output in continuous mode. */
static void latch_output(fake_lsm303dlhc_mag_t *const fake) {
  if ((fake->registers[REG_MR] & 0x03u) != 0u) {
    return;
  }
  int16_t counts[3];
  field_counts(fake, counts);
  const int16_t chip_order[3] = {counts[0], counts[2], counts[1]}; /* X, Z, Y */
  for (unsigned i = 0u; i < 3u; i++) {
    const uint16_t value = (uint16_t)chip_order[i];
    fake->registers[REG_OUT_X_H + 2u * i] = (uint8_t)(value >> 8);
    fake->registers[REG_OUT_X_H + 2u * i + 1u] = (uint8_t)value;
  }
}

static uint8_t next_pointer(uint8_t pointer) {
  if (pointer == REG_OUT_Y_L) {
    return REG_OUT_X_H;
  }
  if (pointer == REG_IRC) {
    return REG_CRA;
  }
  return (uint8_t)(pointer + 1u);
}

static bus_status_t fake_read(void *context, uint8_t device, uint8_t reg, uint8_t *data,
                              size_t length) {
  fake_lsm303dlhc_mag_t *const fake = context;
  if (!fake->present || device != fake->address) {
    return BUS_NACK;
  }
  fake->read_transfers++;
  latch_output(fake);
  fake->pointer = reg;
  for (size_t i = 0u; i < length; i++) {
    data[i] = fake->pointer < FAKE_LSM303DLHC_MAG_REGISTERS ? fake->registers[fake->pointer] : 0u;
    fake->pointer = next_pointer(fake->pointer);
  }
  return BUS_OK;
}

static bool writable(uint8_t reg) {
  return reg <= REG_MR || reg == REG_SR || (reg >= REG_IRA && reg <= REG_IRC);
}

static bus_status_t fake_write(void *context, uint8_t device, uint8_t reg, const uint8_t *data,
                               size_t length) {
  fake_lsm303dlhc_mag_t *const fake = context;
  if (!fake->present || device != fake->address) {
    return BUS_NACK;
  }
  fake->write_transfers++;
  fake->pointer = reg;
  if (length != 1u || !writable(reg)) {
    fake->protocol_errors++; /* the chip would write every byte to one register */
    return BUS_OK;
  }
  if (!fake->ignore_writes) {
    fake->registers[reg] = data[0];
  }
  return BUS_OK;
}

static void fake_delay_us(void *context, uint32_t microseconds) {
  fake_lsm303dlhc_mag_t *const fake = context;
  fake->time_us += microseconds;
}

static uint32_t fake_now_us(void *context) {
  const fake_lsm303dlhc_mag_t *const fake = context;
  return fake->time_us;
}

bus_t fake_lsm303dlhc_mag_bus(fake_lsm303dlhc_mag_t *const fake) {
  return (bus_t){.read = fake_read,
                 .write = fake_write,
                 .delay_us = fake_delay_us,
                 .now_us = fake_now_us,
                 .context = fake};
}
