/* The QEMU node: the node application (core/node.h) on the lm3s6965evb.
 *   - CAN: SLCAN text on UART0 (decoded in the main loop from the receive interrupt's
 *     ring buffer; frames are sent only once the host opened the channel with `O`);
 *   - magnetometer: the LSM303DLHC behind the real I2C0 master (QEMU's lsm303dlhc_mag);
 *   - IMU: the ICM-42688-P's register-level fake (imu_sim.h: QEMU has no such model);
 *   - log: every output sample's values before packing, one line each on UART1:
 *       out SEQ TIME_US QW QX QY QZ AX AY AZ FLAGS
 *     seq and time in decimal, floats as the hex of their IEEE 754 bits (exact), flags
 *     bit 0 orientation_invalid, 1 acc_clipped, 2 mag_disturbed. */
#include <stdbool.h>
#include <stdint.h>

#include "board.h"
#include "board_text.h"
#include "cortex_m.h"
#include "imu_sim.h"
#include "lsm303dlhc_mag.h"
#include "node.h"
#include "slcan.h"

#define QEMU_NODE_ID 7u

typedef struct {
  node_t node;
  imu_sim_t imu;
  bus_t imu_bus;
  bus_t mag_bus;
  slcan_decoder_t slcan;
} qemu_node_t;

static qemu_node_t board_node;

static void log_word(const char *text) {
  board_uart1_write(" ", 1u);
  board_uart1_write_text(text);
}

static void log_float(float value) {
  char bits[9];
  board_text_float_bits(value, bits);
  log_word(bits);
}

static void log_output(void *context, const node_output_t *output) {
  (void)context;
  char number[BOARD_TEXT_U32_MAX];
  board_uart1_write_text("out");
  board_text_u32(output->seq, number);
  log_word(number);
  board_text_u32(output->time_us, number);
  log_word(number);
  for (unsigned i = 0u; i < 4u; i++) {
    log_float(output->q_wxyz[i]);
  }
  for (unsigned i = 0u; i < 3u; i++) {
    log_float(output->acc_mps2[i]);
  }
  const uint32_t flags = (output->orientation_invalid ? 1u : 0u) |
                         (output->acc_clipped ? 2u : 0u) | (output->mag_disturbed ? 4u : 0u);
  board_text_u32(flags, number);
  log_word(number);
  board_uart1_write("\n", 1u);
}

/* Characters received on UART0 into the SLCAN decoder: frames to the node (stamped
 * with their last character's arrival), command answers back to the host. */
static void receive_slcan(qemu_node_t *const qemu_node) {
  board_rx_t received;
  while (board_uart0_receive(&received)) {
    can_frame_t frame;
    char reply[SLCAN_MAX_REPLY];
    size_t reply_length = 0u;
    const slcan_event_t event =
        slcan_decoder_push(&qemu_node->slcan, received.character, &frame, reply, &reply_length);
    if (event == SLCAN_FRAME) {
      node_receive(&qemu_node->node, &frame, received.time_us);
    } else if (reply_length > 0u) {
      board_uart0_write(reply, reply_length);
    }
  }
}

static void transmit_slcan(qemu_node_t *const qemu_node) {
  if (!qemu_node->slcan.open) {
    return; /* frames wait in the node's queue (a full queue is reported in the heartbeat) */
  }
  can_frame_t frame;
  while (node_transmit_next(&qemu_node->node, &frame)) {
    char text[SLCAN_MAX_LINE];
    const size_t length = slcan_encode(&frame, text, sizeof text);
    board_uart0_write(text, length);
  }
}

int main(void) {
  board_init();
  qemu_node_t *const qemu_node = &board_node;
  node_settings_t settings = node_settings_default;
  settings.node_id = QEMU_NODE_ID;
  settings.mag_address = LSM303DLHC_MAG_ADDRESS;
  settings.mag_stuck_us = 0u; /* QEMU's magnetometer model has no noise: never "stuck" */
  settings.on_output = log_output;
  settings.output_context = qemu_node;
  board_i2c_init(&qemu_node->mag_bus);
  imu_sim_init(&qemu_node->imu, settings.imu_address, &qemu_node->node, &qemu_node->imu_bus);
  slcan_decoder_init(&qemu_node->slcan);
  node_init(&qemu_node->node, &settings, &qemu_node->imu_bus, &qemu_node->mag_bus);
  for (;;) {
    imu_sim_run(&qemu_node->imu);
    receive_slcan(qemu_node);
    node_poll(&qemu_node->node, board_now_us());
    transmit_slcan(qemu_node);
    cortex_m_wait_for_interrupt(); /* SysTick wakes the loop every millisecond */
  }
}
