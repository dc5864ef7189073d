/* The production node's program: brings the G431 up and runs the node application
 * (core/node.h) between its interrupts and its main loop.
 *
 * Interrupts (same priority, so neither preempts the other, and each feeds its own
 * single-producer queue of the node):
 *   TIM2      INT1 edge captured -> node_imu_interrupt(captured time); 1 ms tick
 *   FDCAN1 0  received frames   -> node_receive(frame, start-of-frame time);
 *             transmission complete and bus-off only wake the loop
 * Main loop: refresh the watchdog, node_poll, then node_transmit_next into the FDCAN
 * transmit FIFO until the node has nothing or the FIFO is full (the frame is then kept
 * and offered again next pass: nothing is dropped here), bus-off recovery, and WFI until
 * an interrupt has something new.
 */
#include <stdbool.h>
#include <stdint.h>

#include "board_config.h"
#include "g4_clock.h"
#include "g4_fdcan.h"
#include "g4_node_id.h"
#include "g4_regs.h"
#include "g4_startup.h"
#include "g4_timer.h"
#include "g4_watchdog.h"
#include "node.h"

/* The provisioning record's place (linker script, NODE_ID region). */
extern const uint32_t g4_node_id_record[G4_NODE_ID_RECORD_WORDS];

typedef struct {
  node_t node;
  node_settings_t settings;
  g4_i2c_t imu_i2c;
  g4_i2c_t mag_i2c;
  bus_t imu_bus;
  bus_t mag_bus;
  g4_fdcan_t can;
  can_frame_t pending;       /* a frame the full transmit FIFO did not take yet */
  bool pending_valid;
  volatile bool wake;        /* an interrupt ran since the loop last looked */
  g4_clock_source_t clock_source;
  g4_node_id_t id;
  uint32_t reset_flags;      /* RCC_CSR at boot: why the node last reset */
  uint32_t imu_edges_missed; /* INT1 edges that came before the previous was read */
} board_t;

/* The one instance: interrupt handlers have no argument to carry it. */
static board_t board;

void board_tim2_isr(void) {
  const g4_timer_events_t events = g4_timer_service();
  if (events.captured) {
    board.imu_edges_missed += events.capture_missed ? 1u : 0u;
    node_imu_interrupt(&board.node, events.capture_us);
  }
  board.wake = true;
}

void board_fdcan1_it0_isr(void) {
  can_frame_t frame;
  uint32_t rx_time_us;
  g4_fdcan_acknowledge(&board.can);
  while (g4_fdcan_receive(&board.can, &frame, &rx_time_us)) {
    node_receive(&board.node, &frame, rx_time_us);
  }
  board.wake = true;
}

static void board_pins(void) {
  G4_RCC_AHB2ENR |= G4_RCC_AHB2ENR_GPIOA | G4_RCC_AHB2ENR_GPIOB | G4_RCC_AHB2ENR_GPIOF;
  (void)G4_RCC_AHB2ENR;
  g4_gpio_write(&board_can_standby, false);
  g4_gpio_configure(&board_can_standby);
  g4_gpio_configure(&board_can_rx);
  g4_gpio_configure(&board_can_tx);
  g4_gpio_configure(&board_imu_int1);
}

static g4_node_id_t board_node_id(void) {
  const uint32_t uid[G4_NODE_ID_UID_WORDS] = {G4_REG(G4_UID_BASE), G4_REG(G4_UID_BASE + 4u),
                                              G4_REG(G4_UID_BASE + 8u)};
  return g4_node_id_resolve(g4_node_id_record, uid);
}

/* Clocks, watchdog, timer, pins, buses, node, CAN. A step that cannot fail on a good
 * board (fixed configuration, checked on the host) resets the node if it does. */
static void board_bring_up(board_t *const b) {
  b->reset_flags = G4_RCC_CSR & G4_RCC_CSR_RESET_FLAGS;
  G4_RCC_CSR |= G4_RCC_CSR_RMVF;
  b->clock_source = g4_clock_init();
  if (b->clock_source == G4_CLOCK_FAILED || !g4_watchdog_start(BOARD_WATCHDOG_MS)) {
    g4_system_reset();
  }
  g4_timer_init(G4_CLOCK_PCLK1_HZ);
  board_pins();
  b->id = board_node_id();
  g4_i2c_init(&b->imu_i2c, &board_imu_i2c);
  g4_i2c_init(&b->mag_i2c, &board_mag_i2c);
  b->imu_bus = g4_i2c_bus(&b->imu_i2c);
  b->mag_bus = g4_i2c_bus(&b->mag_i2c);
  b->settings = node_settings_default;
  b->settings.node_id = b->id.node_id;
  b->settings.clock.interrupt_latency_us = BOARD_INT1_LATENCY_US;
  b->settings.clock.interrupt_jitter_us = BOARD_INT1_JITTER_US;
  node_init(&b->node, &b->settings, &b->imu_bus, &b->mag_bus);
  if (!g4_fdcan_init(&b->can, G4_CLOCK_PCLK1_HZ, b->id.node_id)) {
    g4_system_reset();
  }
  g4_irq_enable(G4_IRQ_TIM2, BOARD_IRQ_PRIORITY);
  g4_irq_enable(G4_IRQ_FDCAN1_IT0, BOARD_IRQ_PRIORITY);
}

/* Every frame the node has, in order, until the transmit FIFO is full. */
static void board_transmit(board_t *const b) {
  for (;;) {
    if (!b->pending_valid) {
      b->pending_valid = node_transmit_next(&b->node, &b->pending);
    }
    if (!b->pending_valid || !g4_fdcan_transmit(&b->pending)) {
      return;
    }
    b->pending_valid = false;
  }
}

static void board_loop_pass(board_t *const b) {
  b->wake = false;
  g4_watchdog_refresh();
  node_poll(&b->node, g4_timer_now_us());
  board_transmit(b);
  g4_fdcan_service(&b->can);
  g4_interrupts_disable(); /* WFI still wakes on a pending interrupt */
  if (!b->wake) {
    g4_wait_for_interrupt();
  }
  g4_interrupts_enable();
}

void board_main(void) {
  board_bring_up(&board);
  g4_interrupts_enable();
  for (;;) {
    board_loop_pass(&board);
  }
}
