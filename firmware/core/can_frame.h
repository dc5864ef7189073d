/* A classic CAN 2.0A data frame, as the node queues it and as the boards send it
 * (FDCAN in classic mode on the production node, SLCAN text on the QEMU node). */
#ifndef FIRMWARE_CORE_CAN_FRAME_H
#define FIRMWARE_CORE_CAN_FRAME_H

#include <stdint.h>

#define CAN_FRAME_MAX_DATA 8u /* bytes: classic CAN */

typedef struct {
  uint16_t id;     /* 11-bit identifier: base of the message + node id (proto/can) */
  uint8_t length;  /* data length code, 0..8 bytes */
  uint8_t data[CAN_FRAME_MAX_DATA];
} can_frame_t;

#endif /* FIRMWARE_CORE_CAN_FRAME_H */
