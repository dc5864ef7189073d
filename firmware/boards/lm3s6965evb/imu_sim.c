/* The QEMU node's IMU: the fake ICM-42688-P on the board's clock (imu_sim.h). */
#include "imu_sim.h"

#include <math.h>

#include "board.h"

#define PI_F 3.14159265f
#define GRAVITY_MPS2 9.80665f
#define YAW_RATE_AMPLITUDE_RADS 0.6f
#define YAW_RATE_FREQUENCY_HZ 0.2f
#define SWAY_AMPLITUDE_MPS2 0.5f
#define SWAY_FREQUENCY_HZ 1.0f

void imu_sim_motion(float time_s, float gyr_rads[3], float acc_mps2[3]) {
  gyr_rads[0] = 0.0f;
  gyr_rads[1] = 0.0f;
  gyr_rads[2] = YAW_RATE_AMPLITUDE_RADS * sinf(2.0f * PI_F * YAW_RATE_FREQUENCY_HZ * time_s);
  acc_mps2[0] = SWAY_AMPLITUDE_MPS2 * sinf(2.0f * PI_F * SWAY_FREQUENCY_HZ * time_s);
  acc_mps2[1] = 0.0f;
  acc_mps2[2] = GRAVITY_MPS2;
}

static void motion_source(void *context, uint32_t sequence, int64_t time_ns, float gyr_rads[3],
                          float acc_mps2[3]) {
  (void)context;
  (void)sequence;
  imu_sim_motion((float)(time_ns / 1000) * 1e-6f, gyr_rads, acc_mps2);
}

static void int1_edge(void *context, int64_t time_ns) {
  imu_sim_t *const sim = context;
  node_imu_interrupt(sim->node, sim->start_us + (uint32_t)(uint64_t)(time_ns / 1000));
}

void imu_sim_run(imu_sim_t *const sim) {
  const uint32_t now_us = board_now_us();
  sim->elapsed_ns += (int64_t)(uint32_t)(now_us - sim->last_us) * 1000;
  sim->last_us = now_us;
  fake_icm42688_advance_to_ns(&sim->chip, sim->elapsed_ns);
}

/* The bus the node sees: the fake's transfers, each at the board's time now. */
static bus_status_t sim_read(void *context, uint8_t device, uint8_t reg, uint8_t *data,
                             size_t length) {
  imu_sim_t *const sim = context;
  imu_sim_run(sim);
  const bus_t chip_bus = fake_icm42688_bus(&sim->chip);
  return chip_bus.read(chip_bus.context, device, reg, data, length);
}

static bus_status_t sim_write(void *context, uint8_t device, uint8_t reg, const uint8_t *data,
                              size_t length) {
  imu_sim_t *const sim = context;
  imu_sim_run(sim);
  const bus_t chip_bus = fake_icm42688_bus(&sim->chip);
  return chip_bus.write(chip_bus.context, device, reg, data, length);
}

static void sim_delay_us(void *context, uint32_t microseconds) {
  (void)context;
  board_delay_us(microseconds);
}

static uint32_t sim_now_us(void *context) {
  (void)context;
  return board_now_us();
}

void imu_sim_init(imu_sim_t *const sim, uint8_t address, node_t *const node, bus_t *const bus) {
  fake_icm42688_init(&sim->chip, address);
  fake_icm42688_set_source(&sim->chip, motion_source, sim);
  fake_icm42688_set_int1(&sim->chip, int1_edge, sim);
  sim->node = node;
  sim->start_us = board_now_us();
  sim->last_us = sim->start_us;
  sim->elapsed_ns = 0;
  *bus = (bus_t){.read = sim_read,
                 .write = sim_write,
                 .delay_us = sim_delay_us,
                 .now_us = sim_now_us,
                 .context = sim};
}
