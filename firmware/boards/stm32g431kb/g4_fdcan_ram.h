/* The G4 FDCAN's message RAM: its fixed layout and its elements (RM0440, "FDCAN message
 * RAM"), as words, without hardware: the host tests check the layout and the packing.
 *
 * Unlike other M_CAN parts, the G4's layout is fixed per instance (no start-address
 * registers): 28 standard filters, 8 extended filters, two receive FIFOs of 3 elements,
 * a transmit event FIFO of 3 and 3 transmit buffers, every frame element 18 words
 * (2 header words and 64 data bytes). This board uses one standard filter, receive
 * FIFO 0 and the 3 transmit buffers as a FIFO.
 */
#ifndef FIRMWARE_BOARDS_STM32G431KB_G4_FDCAN_RAM_H
#define FIRMWARE_BOARDS_STM32G431KB_G4_FDCAN_RAM_H

#include <stdbool.h>
#include <stdint.h>

#include "can_frame.h"

#define G4_FDCAN_RAM_STD_FILTERS 28u
#define G4_FDCAN_RAM_EXT_FILTERS 8u
#define G4_FDCAN_RAM_RX_FIFO_ELEMENTS 3u
#define G4_FDCAN_RAM_TX_EVENT_ELEMENTS 3u
#define G4_FDCAN_RAM_TX_BUFFERS 3u
#define G4_FDCAN_RAM_STD_FILTER_BYTES 4u
#define G4_FDCAN_RAM_EXT_FILTER_BYTES 8u
#define G4_FDCAN_RAM_TX_EVENT_BYTES 8u
#define G4_FDCAN_RAM_ELEMENT_BYTES 72u /* 2 header words + 64 data bytes */
#define G4_FDCAN_RAM_FRAME_WORDS 4u    /* what a classic frame uses: header + 8 bytes */

/* Byte offsets inside one instance's block, in the manual's order. */
#define G4_FDCAN_RAM_STD_FILTER_OFFSET 0u
#define G4_FDCAN_RAM_EXT_FILTER_OFFSET \
  (G4_FDCAN_RAM_STD_FILTER_OFFSET + G4_FDCAN_RAM_STD_FILTERS * G4_FDCAN_RAM_STD_FILTER_BYTES)
#define G4_FDCAN_RAM_RX_FIFO0_OFFSET \
  (G4_FDCAN_RAM_EXT_FILTER_OFFSET + G4_FDCAN_RAM_EXT_FILTERS * G4_FDCAN_RAM_EXT_FILTER_BYTES)
#define G4_FDCAN_RAM_RX_FIFO1_OFFSET \
  (G4_FDCAN_RAM_RX_FIFO0_OFFSET + G4_FDCAN_RAM_RX_FIFO_ELEMENTS * G4_FDCAN_RAM_ELEMENT_BYTES)
#define G4_FDCAN_RAM_TX_EVENT_OFFSET \
  (G4_FDCAN_RAM_RX_FIFO1_OFFSET + G4_FDCAN_RAM_RX_FIFO_ELEMENTS * G4_FDCAN_RAM_ELEMENT_BYTES)
#define G4_FDCAN_RAM_TX_BUFFER_OFFSET \
  (G4_FDCAN_RAM_TX_EVENT_OFFSET + G4_FDCAN_RAM_TX_EVENT_ELEMENTS * G4_FDCAN_RAM_TX_EVENT_BYTES)
#define G4_FDCAN_RAM_INSTANCE_BYTES \
  (G4_FDCAN_RAM_TX_BUFFER_OFFSET + G4_FDCAN_RAM_TX_BUFFERS * G4_FDCAN_RAM_ELEMENT_BYTES)

/* Byte offset of receive FIFO 0 element `index` / transmit buffer `index`. */
uint32_t g4_fdcan_ram_rx_fifo0_offset(uint32_t index);
uint32_t g4_fdcan_ram_tx_buffer_offset(uint32_t index);

/* A standard filter element that stores frames with identifier `id1` or `id2` (a dual-ID
 * filter) in receive FIFO 0. */
uint32_t g4_fdcan_ram_filter_dual_to_fifo0(uint16_t id1, uint16_t id2);

/* A transmit buffer element of a classic data frame: header words and data, little-endian. */
void g4_fdcan_ram_pack_tx(const can_frame_t *const frame,
                          uint32_t words[G4_FDCAN_RAM_FRAME_WORDS]);

/* The frame of a receive element and its 16-bit start-of-frame timestamp. False for what
 * the node never takes (extended identifier, remote frame, CAN FD frame). A classic DLC
 * of 9..15 carries 8 bytes. */
bool g4_fdcan_ram_unpack_rx(const uint32_t words[G4_FDCAN_RAM_FRAME_WORDS],
                            can_frame_t *const frame, uint16_t *const timestamp);

/* The node-timer time of a frame whose start of frame the controller stamped `rx_stamp`,
 * given the node timer `now_us` and the controller's counter `now_stamp` read together:
 * both count microseconds (the counter counts bit times at 1 Mbit/s), so the frame is
 * (now_stamp - rx_stamp) mod 2^16 us old; valid within 65.5 ms of its arrival. */
uint32_t g4_fdcan_ram_rx_time_us(uint32_t now_us, uint16_t now_stamp, uint16_t rx_stamp);

#endif /* FIRMWARE_BOARDS_STM32G431KB_G4_FDCAN_RAM_H */
