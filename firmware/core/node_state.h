/* The node's whole state, owned by the board (one static node_t). Read it through the
 * node_* functions; tests read fields directly. */
#ifndef FIRMWARE_CORE_NODE_STATE_H
#define FIRMWARE_CORE_NODE_STATE_H

#include <stdbool.h>
#include <stdint.h>

#include "bus.h"
#include "can_frame.h"
#include "can_protocol.h"
#include "icm42688.h"
#include "imu_filter.h"
#include "lsm303dlhc_mag.h"
#include "node_config.h"
#include "node_queue.h"
#include "sample_clock.h"

#define NODE_IRQ_QUEUE 16u       /* IMU interrupt times waiting for node_poll */
#define NODE_RX_QUEUE 16u        /* received frames waiting for node_poll */
#define NODE_TX_QUEUE 32u        /* frames waiting for the bus: 14 samples and 4 control frames */
#define NODE_FIFO_BATCH 16u      /* IMU samples per FIFO read (on the stack: 0.5 KiB) */

typedef struct {
  can_frame_t frame;
  uint32_t time_us; /* rx: arrival; tx: the sample's time (stale samples are dropped) */
  bool is_sample;   /* tx: ImuQuat/ImuAccel, dropped when older than NODE_MAX_SAMPLE_AGE_US */
} node_frame_slot_t;

/* Identical readings for this long mean a stuck sensor. */
typedef struct {
  float last[6];          /* the previous reading */
  uint32_t since_us;      /* node time the reading stopped changing */
  bool repeating;         /* the last two readings were identical */
} node_stuck_watch_t;

typedef struct {
  node_settings_t settings;
  const bus_t *imu_bus;
  const bus_t *mag_bus;

  /* Configuration, changed by commands. */
  uint16_t rate_hz;          /* output rate */
  uint8_t acc_range_g;
  uint16_t gyro_range_dps;
  node_mode_t mode;
  bool running;              /* streaming samples */

  /* Chips. */
  icm42688_t imu;
  lsm303dlhc_mag_t mag;
  bool imu_ready;            /* probed, self-tested and configured */
  bool mag_ready;
  bool imu_probed;           /* a probe of the IMU was tried (state leaves BOOT) */
  bool self_test_done;       /* the IMU's self-test runs once, at the first probe */
  bool self_test_failed;     /* ... and its verdict is in every heartbeat */
  uint32_t next_imu_probe_us;
  uint32_t next_mag_probe_us;
  uint32_t next_mag_read_us;
  uint32_t last_fifo_read_us;
  float mag_ut[3];           /* the latest magnetometer reading, uT, in the IMU's axes */
  bool mag_valid;            /* mag_ut is a live reading (not failed, not stuck) */
  bool mag_fresh;            /* mag_ut not given to the filter yet */
  node_stuck_watch_t imu_watch;
  node_stuck_watch_t mag_watch;

  /* Samples: clock, filter, output interval. */
  sample_clock_t clock;
  imu_filter_t filter;
  float nominal_period_us;   /* the IMU's sample period at its nominal rate */
  uint32_t output_phase;     /* rate_hz per IMU sample; an output at each imu_odr_hz */
  uint16_t interval_count;   /* IMU samples in the current output interval */
  float acc_sum_mps2[3];
  bool interval_clipped;
  uint8_t seq;
  uint32_t untimed_outputs;  /* outputs not sent: no interrupt edge since a restart yet */

  /* Health. */
  can_state_t state;
  uint16_t status;           /* can_status_bit_t seen since the last heartbeat */
  uint16_t reported_status;  /* bits already sent in a heartbeat this second */
  uint8_t error_count;
  uint32_t next_heartbeat_us;
  uint32_t last_heartbeat_us;
  bool heartbeat_started;    /* the start-up heartbeat went out */
  uint32_t last_sync_us;
  bool sync_seen;
  uint32_t now_us;           /* the time of the latest node_poll */

  /* Hand-over between interrupts and the main loop. */
  node_queue_t irq_queue;
  uint32_t irq_times_us[NODE_IRQ_QUEUE];
  node_queue_t rx_queue;
  node_frame_slot_t rx_slots[NODE_RX_QUEUE];
  node_queue_t tx_queue;
  node_frame_slot_t tx_slots[NODE_TX_QUEUE];
} node_t;

#endif /* FIRMWARE_CORE_NODE_STATE_H */
