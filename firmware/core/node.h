/* The IMU sensor node's application: everything a node does between its chips and its
 * CAN bus, without any hardware. A board owns one node_t and calls, from
 *   - the IMU's data-ready/watermark interrupt: node_imu_interrupt(time)
 *   - the CAN receive interrupt (or the SLCAN parser): node_receive(frame, time)
 *   - its main loop: node_poll(now), then node_transmit_next() until it returns false.
 * node_poll reads the IMU FIFO and the magnetometer through the drivers (bus_t), stamps
 * every sample on the node's microsecond timer (sample_clock), runs the orientation
 * filter at the IMU's output data rate, and queues the output frames of proto/can.
 *
 * Concurrency: node_imu_interrupt and node_receive may run in interrupt context while
 * node_poll runs in the main loop; each hands over through a single-producer,
 * single-consumer queue, and nothing else is shared.
 */
#ifndef FIRMWARE_CORE_NODE_H
#define FIRMWARE_CORE_NODE_H

#include <stdbool.h>
#include <stdint.h>

#include "bus.h"
#include "can_frame.h"
#include "node_config.h"
#include "node_state.h"

/* Set up the node (chips probed and configured at the first node_poll). */
void node_init(node_t *const node, const node_settings_t *const settings,
               const bus_t *const imu_bus, const bus_t *const mag_bus);

/* The IMU's interrupt line rose at `time_us` (node timer). Interrupt-safe. */
void node_imu_interrupt(node_t *const node, uint32_t time_us);

/* A CAN frame arrived at `rx_time_us` (node timer). Frames addressed to other nodes are
 * ignored; malformed ones are refused and reported. Interrupt-safe. */
void node_receive(node_t *const node, const can_frame_t *const frame, uint32_t rx_time_us);

/* One step of the main loop at `now_us`: commands, sensors, filter, heartbeat. */
void node_poll(node_t *const node, uint32_t now_us);

/* The next frame to send, oldest first; false when none is queued. */
bool node_transmit_next(node_t *const node, can_frame_t *const frame);

#endif /* FIRMWARE_CORE_NODE_H */
