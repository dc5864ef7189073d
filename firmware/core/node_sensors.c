/* The node's sensors: probing and configuring the chips (again after any failure), the
 * IMU's FIFO read on its watermark interrupt, every sample stamped (sample_clock) and fed
 * to the orientation filter at the IMU's rate, and the output interval: the acceleration
 * averaged, the orientation and time of its last sample, two frames queued. */
#include <string.h>

#include "node_internal.h"

static void node_start_interval(node_t *const node) {
  node->interval_count = 0;
  node->interval_clipped = false;
  memset(node->acc_sum_mps2, 0, sizeof(node->acc_sum_mps2));
}

void node_sensors_configure_output(node_t *const node) {
  node->output_phase = 0;
  node_start_interval(node);
}

/* FIFO watermark: about 4 ms of samples, so the sample clock hears interrupts often and
 * the bus gets frames soon. */
static uint16_t node_watermark(const node_t *const node) {
  const uint16_t samples = (uint16_t)(node->settings.imu_odr_hz / 250u);
  return samples < 1u ? 1u : (samples > NODE_FIFO_BATCH / 2u ? NODE_FIFO_BATCH / 2u : samples);
}

static void node_probe_imu(node_t *const node, uint32_t now_us) {
  node->imu_probed = true;
  node->next_imu_probe_us = now_us + NODE_PROBE_INTERVAL_US;
  const icm42688_config_t config = {
      .odr_hz = node->settings.imu_odr_hz,
      .acc_range_g = node->acc_range_g,
      .gyro_range_dps = node->gyro_range_dps,
      .fifo_watermark_samples = node_watermark(node),
  };
  icm42688_status_t status = icm42688_init(&node->imu, node->imu_bus, node->settings.imu_address);
  if (status == ICM42688_WRONG_ID) node->status |= CAN_STATUS_IMU_NACK; /* another chip answers */
  if (status == ICM42688_OK && !node->self_test_done) {
    bool passed = false;
    status = icm42688_self_test(&node->imu, &passed);
    node->self_test_done = status == ICM42688_OK;
    node->self_test_failed = node->self_test_done && !passed;
  }
  if (status == ICM42688_OK) status = icm42688_configure(&node->imu, &config);
  if (status != ICM42688_OK) {
    node->status |= CAN_STATUS_IMU_NACK;
    return;
  }
  node->imu_ready = true;
  node->last_fifo_read_us = now_us;
  node->imu_watch.repeating = false;
  node->nominal_period_us = (float)icm42688_odr_period_us(config.odr_hz);
  sample_clock_restart(&node->clock, icm42688_odr_period_us(config.odr_hz),
                       config.fifo_watermark_samples, node->imu.fifo_flush_us);
}

/* True when `reading` equals the previous one for `limit_us` (0: never). */
static bool node_stuck(node_stuck_watch_t *const watch, const float *reading, unsigned n,
                       uint32_t time_us, uint32_t limit_us) {
  const bool same = memcmp(watch->last, reading, n * sizeof(float)) == 0;
  memcpy(watch->last, reading, n * sizeof(float));
  if (!same) {
    watch->repeating = false;
    return false;
  }
  if (!watch->repeating) {
    watch->repeating = true;
    watch->since_us = time_us;
  }
  return limit_us > 0 && time_us - watch->since_us >= limit_us;
}

static void node_emit(node_t *const node, uint32_t time_us, bool timed) {
  const float n = (float)node->interval_count;
  node_output_t out = {
      .acc_mps2 = {node->acc_sum_mps2[0] / n, node->acc_sum_mps2[1] / n, node->acc_sum_mps2[2] / n},
      .time_us = time_us,
      .seq = node->seq,
      .orientation_invalid = !imu_filter_settled(&node->filter),
      .acc_clipped = node->interval_clipped,
      .mag_disturbed = node->mode == NODE_MODE_9D && imu_filter_mag_disturbed(&node->filter),
  };
  imu_filter_quaternion(&node->filter, out.q_wxyz);
  if (out.acc_clipped) node->status |= CAN_STATUS_ACC_CLIPPED;
  if (out.mag_disturbed) node->status |= CAN_STATUS_MAG_DISTURBED;
  /* A time guessed before the clock's first interrupt edge would mislead the hub. */
  if (!timed) node->untimed_outputs++;
  if (node->running && timed) {
    can_frame_t quat, accel;
    can_protocol_pack_sample(node->settings.node_id, &out, &quat, &accel);
    /* Both frames or neither: the hub pairs them. */
    if (NODE_TX_QUEUE - NODE_CONTROL_RESERVE - node_queue_count(&node->tx_queue) >= 2u) {
      node_queue_frame(node, &quat, time_us, true);
      node_queue_frame(node, &accel, time_us, true);
      if (node->settings.on_output) node->settings.on_output(node->settings.output_context, &out);
    } else {
      node->status |= CAN_STATUS_TX_OVERFLOW;
    }
    node->seq++;
  }
  node_start_interval(node);
}

static void node_sample(node_t *const node, const imu_sample_t *const sample, uint32_t time_us,
                        bool timed) {
  float reading[6];
  memcpy(reading, sample->gyr_rads, sizeof(sample->gyr_rads));
  memcpy(reading + 3, sample->acc_mps2, sizeof(sample->acc_mps2));
  if (node_stuck(&node->imu_watch, reading, 6, time_us, node->settings.imu_stuck_us)) {
    node->status |= CAN_STATUS_IMU_STUCK;
    node->imu_ready = false; /* reset and configured again at once */
    node->next_imu_probe_us = node->now_us;
    return;
  }
  /* The chip's clock is off nominal by up to 2 %: integrate over the measured period. */
  const float scale = sample_clock_period_us(&node->clock) / node->nominal_period_us;
  const float gyr_rads[3] = {sample->gyr_rads[0] * scale, sample->gyr_rads[1] * scale,
                             sample->gyr_rads[2] * scale};
  /* A magnetometer slower than the IMU: each reading is given to the filter once. */
  const bool with_mag = node->mode == NODE_MODE_9D && node->mag_valid && node->mag_fresh;
  node->mag_fresh = false;
  imu_filter_update(&node->filter, gyr_rads, sample->acc_mps2, with_mag ? node->mag_ut : NULL);
  for (int i = 0; i < 3; ++i) node->acc_sum_mps2[i] += sample->acc_mps2[i];
  node->interval_clipped |= sample->acc_clipped;
  node->interval_count++;
  /* Output instants: every imu_odr / rate samples on average (any rate, e.g. 60 Hz of a
   * 1 kHz IMU: intervals of 16 and 17 samples, each output stamped with its own time). */
  node->output_phase += node->rate_hz;
  if (node->output_phase >= node->settings.imu_odr_hz) {
    node->output_phase -= node->settings.imu_odr_hz;
    node_emit(node, time_us, timed);
  }
}

static void node_read_imu(node_t *const node, uint32_t now_us) {
  uint32_t slot;
  bool interrupted = false;
  while (node_queue_peek(&node->irq_queue, NODE_IRQ_QUEUE, &slot)) {
    sample_clock_interrupt(&node->clock, node->irq_times_us[slot]);
    node_queue_release(&node->irq_queue);
    interrupted = true;
  }
  /* Without an interrupt, read anyway after a while: a lost edge must not stall the node. */
  const uint32_t watermark_us = icm42688_odr_period_us(node->settings.imu_odr_hz) * node_watermark(node);
  if (!interrupted && now_us - node->last_fifo_read_us < 4u * watermark_us) return;
  node->last_fifo_read_us = now_us;
  size_t count = NODE_FIFO_BATCH;
  while (count == NODE_FIFO_BATCH && node->imu_ready) {
    imu_sample_t samples[NODE_FIFO_BATCH];
    uint32_t times_us[NODE_FIFO_BATCH];
    bool overflowed = false;
    const uint32_t start_us = node->imu_bus->now_us(node->imu_bus->context);
    const icm42688_status_t status =
        icm42688_read_fifo(&node->imu, samples, NODE_FIFO_BATCH, &count, &overflowed);
    const uint32_t end_us = node->imu_bus->now_us(node->imu_bus->context);
    const bool timed = sample_clock_stamp(&node->clock, start_us, end_us, count, times_us) !=
                       SAMPLE_CLOCK_NO_LOCK;
    for (size_t i = 0; i < count && node->imu_ready; ++i) {
      node_sample(node, &samples[i], times_us[i], timed);
    }
    if (overflowed) { /* the samples above came before the loss; the FIFO was flushed */
      node->status |= CAN_STATUS_FIFO_OVERFLOW;
      sample_clock_restart(&node->clock, icm42688_odr_period_us(node->settings.imu_odr_hz),
                           node_watermark(node), node->imu.fifo_flush_us);
    }
    if (status != ICM42688_OK) {
      node->status |= CAN_STATUS_IMU_NACK;
      node->imu_ready = false;
      node->next_imu_probe_us = now_us + NODE_PROBE_INTERVAL_US / 100u;
      return;
    }
  }
}

static void node_read_mag(node_t *const node, uint32_t now_us) {
  node->next_mag_read_us = now_us + 1000000u / node->settings.mag_rate_hz;
  float field_ut[3];
  const lsm303dlhc_mag_status_t status = lsm303dlhc_mag_read_ut(&node->mag, field_ut);
  if (status == LSM303DLHC_MAG_NACK || status == LSM303DLHC_MAG_BUS_ERROR ||
      status == LSM303DLHC_MAG_WRONG_ID || status == LSM303DLHC_MAG_CONFIG_LOST) {
    node->status |= CAN_STATUS_MAG_NACK;
    node->mag_valid = false;
    node->next_mag_read_us = now_us + NODE_PROBE_INTERVAL_US;
    return;
  }
  if (status != LSM303DLHC_MAG_OK) return; /* an overflowed axis: keep the last field */
  for (int i = 0; i < 3; ++i) {
    const int8_t axis = node->settings.mag_axes[i];
    const float value = field_ut[(axis < 0 ? -axis : axis) - 1];
    node->mag_ut[i] = axis < 0 ? -value : value;
  }
  node->mag_fresh = true;
  node->mag_valid = !node_stuck(&node->mag_watch, node->mag_ut, 3, now_us, node->settings.mag_stuck_us);
  if (!node->mag_valid) {
    node->status |= CAN_STATUS_MAG_STUCK;
    node->mag_watch.repeating = false;
    lsm303dlhc_mag_init(&node->mag, node->mag_bus, node->settings.mag_address,
                        &lsm303dlhc_mag_settings_default); /* configured again at the next read */
  }
}

void node_sensors_poll(node_t *const node, uint32_t now_us) {
  if (node->mode == NODE_MODE_9D && node_time_reached(now_us, node->next_mag_read_us)) {
    node_read_mag(node, now_us);
  }
  if (!node->imu_ready && node_time_reached(now_us, node->next_imu_probe_us)) {
    node_probe_imu(node, now_us);
  }
  if (node->imu_ready) node_read_imu(node, now_us);
}
