/* FDCAN1 in classic CAN mode (ISO 11898-1 CAN 2.0A frames) at 1 Mbit/s, RM0440 "FDCAN".
 *
 * - Kernel clock PCLK1 (170 MHz), bit timing from g4_fdcan_timing (170 tq, sample point
 *   87.6 %), automatic retransmission on.
 * - Acceptance: one dual-ID standard filter passes the Sync (0x080) and this node's
 *   Command (0x600 + id) into receive FIFO 0; every other standard frame, every extended
 *   and every remote frame is rejected in hardware. FIFO 0 blocks when full (3 frames)
 *   and counts the loss; its new-message interrupt (line 0) drains it.
 * - Receive time: the controller stamps each frame at its start of frame on its own
 *   counter of bit times (1 us at 1 Mbit/s); the interrupt turns that stamp into the
 *   node's microsecond time (g4_fdcan_ram_rx_time_us), so interrupt latency adds no
 *   jitter. A start-up check that the counter runs at 1 MHz falls back to the interrupt's
 *   time if it does not.
 * - Transmission: the 3 transmit buffers as a FIFO (sent in the order queued); a full
 *   FIFO refuses the frame, which the caller keeps. Transmission-complete and bus-off
 *   raise line 0 too, to wake the main loop; g4_fdcan_service recovers from bus-off.
 */
#ifndef FIRMWARE_BOARDS_STM32G431KB_G4_FDCAN_H
#define FIRMWARE_BOARDS_STM32G431KB_G4_FDCAN_H

#include <stdbool.h>
#include <stdint.h>

#include "can_frame.h"

#define G4_FDCAN_BITRATE_BPS 1000000u
#define G4_FDCAN_SAMPLE_POINT_PERMILLE 875u /* CiA 301's recommendation at 1 Mbit/s */
#define G4_FDCAN_SYNC_ID 0x080u
#define G4_FDCAN_COMMAND_BASE_ID 0x600u

typedef struct {
  uint32_t nbtp;            /* the bit timing in force */
  bool frame_stamps;        /* start-of-frame stamps in use (false: interrupt time) */
  uint32_t rx_lost;         /* frames the full receive FIFO refused */
  uint32_t rx_rejected;     /* frames the filter passed that the node never takes */
  uint32_t bus_off;         /* bus-off events recovered from */
} g4_fdcan_t;

/* Configures and starts FDCAN1 for `node_id`; false if the controller did not answer or
 * no bit timing fits `kernel_hz`. Interrupt line 0 is enabled in the controller; the NVIC
 * is the caller's. */
bool g4_fdcan_init(g4_fdcan_t *const can, uint32_t kernel_hz, uint8_t node_id);

/* Queues a frame; false (frame not taken) when the transmit FIFO is full. */
bool g4_fdcan_transmit(const can_frame_t *const frame);

/* From the line 0 interrupt: clears its flags; counts losses. */
void g4_fdcan_acknowledge(g4_fdcan_t *const can);

/* Takes the oldest received frame and its node time; false when FIFO 0 is empty. */
bool g4_fdcan_receive(g4_fdcan_t *const can, can_frame_t *const frame, uint32_t *const rx_time_us);

/* From the main loop: restarts the controller after bus-off (it then waits for 129
 * occurrences of 11 recessive bits, as the standard requires). */
void g4_fdcan_service(g4_fdcan_t *const can);

#endif /* FIRMWARE_BOARDS_STM32G431KB_G4_FDCAN_H */
