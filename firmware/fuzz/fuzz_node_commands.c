/* libFuzzer target: the node application's receive path (node.c, node_commands.c) with no
 * chip attached, fed any sequence of frames and timer steps. Input: records [kind][...]:
 * kind % 4 == 0..1: a frame [id low][id high][length][8 data bytes], 2: a timer step [u16 ms] then node_poll, 3: the IMU's
 * interrupt. Checks: every frame the node sends is a valid classic frame of this node, a
 * command reply answers a command, and the node keeps its configuration in range. */
#include <stdlib.h>
#include <string.h>

#include "node.h"
#include "node_internal.h"

#define NODE_ID 5u

static bus_status_t absent_read(void *context, uint8_t device, uint8_t reg, uint8_t *data,
                                size_t length) {
  (void)context, (void)device, (void)reg, (void)data, (void)length;
  return BUS_NACK;
}

static bus_status_t absent_write(void *context, uint8_t device, uint8_t reg,
                                 const uint8_t *data, size_t length) {
  (void)context, (void)device, (void)reg, (void)data, (void)length;
  return BUS_NACK;
}

static void no_delay(void *context, uint32_t microseconds) { (void)context, (void)microseconds; }
static uint32_t no_clock(void *context) { (void)context; return 0; }

static const bus_t absent_bus = {absent_read, absent_write, no_delay, no_clock, NULL};

static void drain(node_t *const node) {
  can_frame_t frame;
  while (node_transmit_next(node, &frame)) {
    if (frame.length > CAN_FRAME_MAX_DATA || (frame.id & CAN_NODE_ID_MASK) != NODE_ID) abort();
  }
  if (node->rate_hz == 0 || node->rate_hz > NODE_MAX_RATE_HZ || node->mode > NODE_MODE_9D) abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  static node_t node;
  memset(&node, 0, sizeof(node));
  node_settings_t settings = node_settings_default;
  settings.node_id = NODE_ID;
  node_init(&node, &settings, &absent_bus, &absent_bus);
  uint32_t now_us = 0;
  size_t at = 0;
  while (at < size) {
    const uint8_t kind = data[at++] % 4u;
    if (kind <= 1 && at + 11 <= size) {
      can_frame_t frame;
      frame.id = (uint16_t)((data[at] | (data[at + 1] << 8)) & 0x7FFu);
      frame.length = data[at + 2] & 0x0Fu;
      memcpy(frame.data, data + at + 3, CAN_FRAME_MAX_DATA);
      at += 11;
      node_receive(&node, &frame, now_us);
    } else if (kind == 2 && at + 2 <= size) {
      now_us += 1000u * (uint32_t)(data[at] | (data[at + 1] << 8));
      at += 2;
      node_poll(&node, now_us);
      drain(&node);
    } else if (kind == 3) {
      node_imu_interrupt(&node, now_us);
    } else {
      break;
    }
  }
  node_poll(&node, now_us);
  drain(&node);
  return 0;
}
