/* The node application: set-up, the hand-over from interrupts, the main loop's order and
 * the transmit queue. Commands: node_commands.c; chips, filter and samples:
 * node_sensors.c; heartbeat: node_health.c. */
#include "node.h"

#include <string.h>

#include "node_internal.h"

const node_settings_t node_settings_default = {
    .node_id = 1,
    .imu_address = 0x68,
    .mag_address = 0x1E,
    .imu_odr_hz = 1000,
    .rate_hz = 100,
    .acc_range_g = 16,
    .gyro_range_dps = 2000,
    .mode = NODE_MODE_9D,
    .mag_rate_hz = 100,
    .mag_axes = {1, 2, 3},
    .imu_stuck_us = 250000,
    .clock = {.interrupt_latency_us = 0.0f, .interrupt_jitter_us = 10.0f, .max_rate_error = 0.03f,
              .settle_interrupts = 32},
    .mag_stuck_us = 1000000,
    .start_running = false,
    .on_output = NULL,
    .output_context = NULL,
};

void node_init(node_t *const node, const node_settings_t *const settings,
               const bus_t *const imu_bus, const bus_t *const mag_bus) {
  memset(node, 0, sizeof(*node));
  node->settings = *settings;
  node->imu_bus = imu_bus;
  node->mag_bus = mag_bus;
  node->rate_hz = settings->rate_hz;
  node->acc_range_g = settings->acc_range_g;
  node->gyro_range_dps = settings->gyro_range_dps;
  node->mode = settings->mode;
  node->running = settings->start_running;
  node->state = CAN_STATE_BOOT;
  lsm303dlhc_mag_init(&node->mag, mag_bus, settings->mag_address, &lsm303dlhc_mag_settings_default);
  sample_clock_init(&node->clock, &settings->clock);
  imu_filter_init(&node->filter, &imu_filter_settings_default, 1.0f / (float)settings->imu_odr_hz);
  node_sensors_configure_output(node);
}

void node_imu_interrupt(node_t *const node, uint32_t time_us) {
  uint32_t slot;
  if (!node_queue_reserve(&node->irq_queue, NODE_IRQ_QUEUE, &slot)) return;
  node->irq_times_us[slot] = time_us;
  node_queue_commit(&node->irq_queue);
}

void node_receive(node_t *const node, const can_frame_t *const frame, uint32_t rx_time_us) {
  uint32_t slot;
  if (!node_queue_reserve(&node->rx_queue, NODE_RX_QUEUE, &slot)) return;
  node->rx_slots[slot].frame = *frame;
  node->rx_slots[slot].time_us = rx_time_us;
  node_queue_commit(&node->rx_queue);
}

void node_poll(node_t *const node, uint32_t now_us) {
  node->now_us = now_us;
  uint32_t slot;
  while (node_queue_peek(&node->rx_queue, NODE_RX_QUEUE, &slot)) {
    const node_frame_slot_t received = node->rx_slots[slot];
    node_queue_release(&node->rx_queue);
    node_handle_frame(node, &received.frame, received.time_us);
  }
  node_sensors_poll(node, now_us);
  node_health_poll(node, now_us);
}

bool node_queue_frame(node_t *const node, const can_frame_t *const frame, uint32_t time_us,
                      bool is_sample) {
  const uint32_t limit = is_sample ? NODE_TX_QUEUE - NODE_CONTROL_RESERVE : NODE_TX_QUEUE;
  uint32_t slot;
  if (node_queue_count(&node->tx_queue) >= limit ||
      !node_queue_reserve(&node->tx_queue, NODE_TX_QUEUE, &slot)) {
    node->status |= CAN_STATUS_TX_OVERFLOW;
    return false;
  }
  node->tx_slots[slot] = (node_frame_slot_t){.frame = *frame, .time_us = time_us, .is_sample = is_sample};
  node_queue_commit(&node->tx_queue);
  return true;
}

bool node_transmit_next(node_t *const node, can_frame_t *const frame) {
  uint32_t slot;
  while (node_queue_peek(&node->tx_queue, NODE_TX_QUEUE, &slot)) {
    const node_frame_slot_t queued = node->tx_slots[slot];
    node_queue_release(&node->tx_queue);
    /* The hub restores a sample's time only while it is fresh: a bus that held it back
     * too long costs the sample, not a wrong time. */
    if (queued.is_sample && (int32_t)(node->now_us - queued.time_us) > (int32_t)NODE_MAX_SAMPLE_AGE_US) {
      node->status |= CAN_STATUS_TX_OVERFLOW;
      continue;
    }
    *frame = queued.frame;
    return true;
  }
  return false;
}
