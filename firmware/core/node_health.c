/* The node's heartbeat: state, configuration and the status bits seen since the previous
 * heartbeat, once a second and early (at most 10 Hz) when a new bit rises. */
#include "node_internal.h"

static can_state_t node_state_now(const node_t *const node) {
  if (!node->imu_ready) return node->imu_probed ? CAN_STATE_FAULT : CAN_STATE_BOOT;
  return node->running ? CAN_STATE_RUNNING : CAN_STATE_IDLE;
}

static void node_send_heartbeat(node_t *const node, uint32_t now_us) {
  const can_heartbeat_t heartbeat = {
      .state = node->state,
      .mode = node->mode,
      .synced = node->sync_seen && now_us - node->last_sync_us < NODE_SYNC_TIMEOUT_US,
      .chip = node->imu_ready ? CAN_CHIP_ICM42688P : CAN_CHIP_NONE,
      .rate_hz = node->rate_hz,
      .status = (uint16_t)(node->status | (node->self_test_failed ? CAN_STATUS_SELF_TEST_FAILED : 0u)),
      .error_count = node->error_count,
  };
  can_frame_t frame;
  can_protocol_pack_heartbeat(node->settings.node_id, &heartbeat, &frame);
  if (!node_queue_frame(node, &frame, now_us, false)) return; /* tried again next poll */
  node->reported_status = node->status;
  node->status = 0;
  node->last_heartbeat_us = now_us;
  node->heartbeat_started = true;
  node->next_heartbeat_us = now_us + NODE_HEARTBEAT_INTERVAL_US;
}

void node_health_poll(node_t *const node, uint32_t now_us) {
  const can_state_t state = node_state_now(node);
  const bool changed = state != node->state;
  node->state = state;
  const bool rising = (node->status & ~node->reported_status) != 0 || changed;
  const bool due = !node->heartbeat_started || node_time_reached(now_us, node->next_heartbeat_us);
  const bool early = rising && now_us - node->last_heartbeat_us >= NODE_HEARTBEAT_MIN_GAP_US;
  if (due || early) node_send_heartbeat(node, now_us);
}
