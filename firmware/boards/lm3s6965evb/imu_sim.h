/* The QEMU node's IMU: QEMU models no accelerometer or gyroscope, so the node's IMU bus
 * leads to the register-level fake of the ICM-42688-P (tests/support/fake_icm42688),
 * compiled into the image and fed with a deterministic synthetic motion.
 *
 * The fake runs on the board's microsecond timer: every transfer first advances it to
 * the board's time, and the main loop advances it too (imu_sim_run), so it samples at
 * its ODR in real (virtual) time. Its INT1 edges are handed to the node stamped with the
 * edge's own time, as a timer capture of the interrupt line would stamp them. */
#ifndef FIRMWARE_BOARDS_LM3S6965EVB_IMU_SIM_H
#define FIRMWARE_BOARDS_LM3S6965EVB_IMU_SIM_H

#include <stdint.h>

#include "bus.h"
#include "fake_icm42688.h"
#include "node.h"

typedef struct {
  fake_icm42688_t chip;
  uint32_t start_us;   /* board timer at the fake's time 0 */
  uint32_t last_us;    /* board timer at the last advance */
  int64_t elapsed_ns;  /* the fake's time at the last advance */
  node_t *node;        /* receives the INT1 edges */
} imu_sim_t;

/* The fake chip at 7-bit `address`, powered on now; `bus` leads to it. */
void imu_sim_init(imu_sim_t *const sim, uint8_t address, node_t *const node, bus_t *const bus);

/* Runs the fake chip up to the board's time now (samples, FIFO, INT1 edges). */
void imu_sim_run(imu_sim_t *const sim);

/* The synthetic motion at `time_s`: turning about z (up) at a varying rate, with a
 * back-and-forth translation along x; gravity +9.80665 m/s^2 on z. */
void imu_sim_motion(float time_s, float gyr_rads[3], float acc_mps2[3]);

#endif /* FIRMWARE_BOARDS_LM3S6965EVB_IMU_SIM_H */
