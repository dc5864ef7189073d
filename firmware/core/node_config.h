/* The node's settings (fixed at start-up by the board) and its output sample. */
#ifndef FIRMWARE_CORE_NODE_CONFIG_H
#define FIRMWARE_CORE_NODE_CONFIG_H

#include <stdbool.h>
#include <stdint.h>

#include "sample_clock.h"

#define NODE_FIRMWARE_VERSION_MAJOR 1u
#define NODE_FIRMWARE_VERSION_MINOR 0u

typedef enum { NODE_MODE_6D = 0, NODE_MODE_9D = 1 } node_mode_t;

/* One output sample, as the node packs it into ImuQuat + ImuAccel (before quantisation). */
typedef struct {
  float q_wxyz[4];       /* orientation, sensor frame -> earth frame (ENU), w first */
  float acc_mps2[3];     /* specific force, sensor frame, mean over the output interval */
  uint32_t time_us;      /* node timer at the sample (the quaternion's time) */
  uint8_t seq;           /* output sample counter, wraps at 256 */
  bool orientation_invalid; /* the filter has not settled, or the IMU failed */
  bool acc_clipped;         /* the accelerometer saturated during the interval */
  bool mag_disturbed;       /* 9D: heading held on the gyroscope */
} node_output_t;

typedef struct {
  uint8_t node_id;          /* 1..63: the CAN identifiers are base + node_id */
  uint8_t imu_address;      /* 7-bit bus address of the 6-axis IMU */
  uint8_t mag_address;      /* 7-bit bus address of the magnetometer */
  uint16_t imu_odr_hz;      /* the IMU's output data rate, which the filter runs at, Hz */
  uint16_t rate_hz;         /* output rate at start-up, Hz (1..400, at most imu_odr_hz) */
  uint8_t acc_range_g;      /* accelerometer full scale at start-up, g */
  uint16_t gyro_range_dps;  /* gyroscope full scale at start-up, deg/s */
  node_mode_t mode;         /* 6D or 9D at start-up */
  uint16_t mag_rate_hz;     /* magnetometer read rate, Hz */
  int8_t mag_axes[3];       /* the board's layout: IMU axis i = sign(v) * magnetometer axis
                               |v| (1 x, 2 y, 3 z), v = mag_axes[i] */
  uint32_t imu_stuck_us;    /* identical IMU readings this long mean a stuck chip, us (0: never) */
  uint32_t mag_stuck_us;    /* the same for the magnetometer, us (0: never; a model without noise) */
  bool start_running;       /* stream at power-up without waiting for START */
  sample_clock_settings_t clock; /* the board's interrupt latency and jitter */
  /* Optional observer of every output sample queued (a board's log, a test); NULL: none. */
  void (*on_output)(void *context, const node_output_t *output);
  void *output_context;
} node_settings_t;

/* 1 kHz IMU, 100 Hz output, +-16 g, +-2000 deg/s, 9D, waits for START. */
extern const node_settings_t node_settings_default;

#endif /* FIRMWARE_CORE_NODE_CONFIG_H */
