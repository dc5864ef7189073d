/* What the node's files share (node.c, node_commands.c, node_sensors.c, node_health.c);
 * not for boards. */
#ifndef FIRMWARE_CORE_NODE_INTERNAL_H
#define FIRMWARE_CORE_NODE_INTERNAL_H

#include <stdbool.h>
#include <stdint.h>

#include "node.h"

#define NODE_MAX_RATE_HZ 400u               /* bus budget: proto/can/README.md */
#define NODE_MAX_SAMPLE_AGE_US 30000u       /* the hub restores sample times up to 65 ms old */
#define NODE_PROBE_INTERVAL_US 1000000u     /* an absent chip is tried again every second */
#define NODE_HEARTBEAT_INTERVAL_US 1000000u
#define NODE_HEARTBEAT_MIN_GAP_US 100000u   /* a rising status bit sends one early, at most 10 Hz */
#define NODE_SYNC_TIMEOUT_US 2000000u
#define NODE_CONTROL_RESERVE 4u             /* tx slots samples leave free for replies and heartbeats */

/* now_us has reached (or passed) deadline_us, across the timer's wrap. */
static inline bool node_time_reached(uint32_t now_us, uint32_t deadline_us) {
  return (int32_t)(now_us - deadline_us) >= 0;
}

/* Queues a frame to send; false (and tx_overflow) when the queue is full. */
bool node_queue_frame(node_t *const node, const can_frame_t *const frame, uint32_t time_us,
                      bool is_sample);
void node_handle_frame(node_t *const node, const can_frame_t *const frame, uint32_t rx_time_us);
void node_sensors_poll(node_t *const node, uint32_t now_us);
void node_sensors_configure_output(node_t *const node); /* after a rate or mode change */
void node_health_poll(node_t *const node, uint32_t now_us);

#endif /* FIRMWARE_CORE_NODE_INTERNAL_H */
