/* FDCAN1 in classic CAN mode (g4_fdcan.h). Message RAM contents: g4_fdcan_ram.c. */
#include "g4_fdcan.h"

#include "g4_fdcan_ram.h"
#include "g4_fdcan_timing.h"
#include "g4_regs.h"
#include "g4_timer.h"

#define FDCAN_CCCR G4_REG(G4_FDCAN1_BASE + 0x018u)
#define FDCAN_NBTP G4_REG(G4_FDCAN1_BASE + 0x01Cu)
#define FDCAN_TSCC G4_REG(G4_FDCAN1_BASE + 0x020u)
#define FDCAN_TSCV G4_REG(G4_FDCAN1_BASE + 0x024u)
#define FDCAN_PSR G4_REG(G4_FDCAN1_BASE + 0x044u)
#define FDCAN_IR G4_REG(G4_FDCAN1_BASE + 0x050u)
#define FDCAN_IE G4_REG(G4_FDCAN1_BASE + 0x054u)
#define FDCAN_ILS G4_REG(G4_FDCAN1_BASE + 0x058u)
#define FDCAN_ILE G4_REG(G4_FDCAN1_BASE + 0x05Cu)
#define FDCAN_RXGFC G4_REG(G4_FDCAN1_BASE + 0x080u)
#define FDCAN_RXF0S G4_REG(G4_FDCAN1_BASE + 0x090u)
#define FDCAN_RXF0A G4_REG(G4_FDCAN1_BASE + 0x094u)
#define FDCAN_TXBC G4_REG(G4_FDCAN1_BASE + 0x0C0u)
#define FDCAN_TXFQS G4_REG(G4_FDCAN1_BASE + 0x0C4u)
#define FDCAN_TXBAR G4_REG(G4_FDCAN1_BASE + 0x0CCu)
#define FDCAN_TXBTIE G4_REG(G4_FDCAN1_BASE + 0x0DCu)
#define FDCAN_CKDIV G4_REG(G4_FDCAN_CONFIG_BASE + 0x000u)
#define FDCAN_RAM(byte_offset) G4_REG(G4_SRAMCAN_BASE + (byte_offset)) /* FDCAN1's block */

#define CCCR_INIT (1u << 0)
#define CCCR_CCE (1u << 1)
#define TSCC_INTERNAL_COUNTER 1u /* TSS = 01, TCP = 0: one count per bit time */
#define PSR_BO (1u << 7)
#define IR_RF0N (1u << 0)
#define IR_RF0L (1u << 2)
#define IR_TC (1u << 7)
#define IR_BO (1u << 19)
#define IR_HANDLED (IR_RF0N | IR_RF0L | IR_TC | IR_BO)
#define ILE_EINT0 (1u << 0)
#define RXGFC_RRFE (1u << 0)          /* reject remote frames, extended */
#define RXGFC_RRFS (1u << 1)          /* and standard */
#define RXGFC_ANFE_REJECT (2u << 2)   /* non-matching extended: reject */
#define RXGFC_ANFS_REJECT (2u << 4)   /* non-matching standard: reject */
#define RXGFC_LSS_SHIFT 16u           /* number of standard filters */
#define RXF0S_FILL_MASK 0xFu
#define RXF0S_GET_SHIFT 8u
#define RXF0S_INDEX_MASK 0x3u
#define TXFQS_PUT_SHIFT 16u
#define TXFQS_INDEX_MASK 0x3u
#define TXFQS_FULL (1u << 21)
#define TXBTIE_ALL ((1u << G4_FDCAN_RAM_TX_BUFFERS) - 1u)
#define RCC_CCIPR_FDCANSEL_SHIFT 24u
#define RCC_CCIPR_FDCANSEL_PCLK1 2u

#define MODE_CHANGE_TIMEOUT_US 10000u
#define STAMP_CHECK_US 1000u
#define STAMP_CHECK_SLACK_US 5u

/* Waits until CCCR.INIT reads `set`, bounded. */
static bool g4_fdcan_wait_init(bool set) {
  const uint32_t start_us = g4_timer_now_us();
  while (((FDCAN_CCCR & CCCR_INIT) != 0u) != set) {
    if (g4_timer_now_us() - start_us > MODE_CHANGE_TIMEOUT_US) {
      return false;
    }
  }
  return true;
}

static void g4_fdcan_configure_ram(uint8_t node_id) {
  for (uint32_t offset = 0u; offset < G4_FDCAN_RAM_INSTANCE_BYTES; offset += 4u) {
    FDCAN_RAM(offset) = 0u; /* the RAM powers up with random contents */
  }
  FDCAN_RAM(G4_FDCAN_RAM_STD_FILTER_OFFSET) =
      g4_fdcan_ram_filter_dual_to_fifo0(G4_FDCAN_SYNC_ID, (uint16_t)(G4_FDCAN_COMMAND_BASE_ID + node_id));
  FDCAN_RXGFC = (1u << RXGFC_LSS_SHIFT) | RXGFC_ANFS_REJECT | RXGFC_ANFE_REJECT | RXGFC_RRFS |
                RXGFC_RRFE; /* FIFO 0 in blocking mode */
  FDCAN_TXBC = 0u;          /* TFQM = 0: transmit FIFO */
}

/* True if the stamp counter counts microseconds alongside TIM2. */
static bool g4_fdcan_stamps_run(void) {
  const uint16_t stamp_start = (uint16_t)FDCAN_TSCV;
  const uint32_t start_us = g4_timer_now_us();
  g4_timer_delay_us(STAMP_CHECK_US);
  const uint16_t counted = (uint16_t)((uint16_t)FDCAN_TSCV - stamp_start);
  const uint32_t elapsed_us = g4_timer_now_us() - start_us;
  return counted + STAMP_CHECK_SLACK_US >= elapsed_us && counted <= elapsed_us + STAMP_CHECK_SLACK_US;
}

bool g4_fdcan_init(g4_fdcan_t *const can, uint32_t kernel_hz, uint8_t node_id) {
  g4_fdcan_timing_t timing;
  *can = (g4_fdcan_t){0};
  if (!g4_fdcan_timing_compute(kernel_hz, G4_FDCAN_BITRATE_BPS, G4_FDCAN_SAMPLE_POINT_PERMILLE, &timing)) {
    return false;
  }
  can->nbtp = g4_fdcan_timing_nbtp(&timing);
  G4_RCC_CCIPR = (G4_RCC_CCIPR & ~(3u << RCC_CCIPR_FDCANSEL_SHIFT)) |
                 (RCC_CCIPR_FDCANSEL_PCLK1 << RCC_CCIPR_FDCANSEL_SHIFT);
  G4_RCC_APB1ENR1 |= G4_RCC_APB1ENR1_FDCAN;
  (void)G4_RCC_APB1ENR1;
  FDCAN_CCCR |= CCCR_INIT;
  if (!g4_fdcan_wait_init(true)) {
    return false;
  }
  FDCAN_CCCR = CCCR_INIT | CCCR_CCE; /* classic CAN, retransmission on, no test modes */
  FDCAN_CKDIV = 0u;                  /* kernel clock undivided */
  FDCAN_NBTP = can->nbtp;
  FDCAN_TSCC = TSCC_INTERNAL_COUNTER;
  g4_fdcan_configure_ram(node_id);
  FDCAN_IE = IR_HANDLED;
  FDCAN_ILS = 0u; /* every group on line 0 */
  FDCAN_TXBTIE = TXBTIE_ALL;
  FDCAN_ILE = ILE_EINT0;
  FDCAN_CCCR &= ~CCCR_INIT; /* CCE clears with it */
  if (!g4_fdcan_wait_init(false)) {
    return false;
  }
  can->frame_stamps = g4_fdcan_stamps_run();
  return true;
}

bool g4_fdcan_transmit(const can_frame_t *const frame) {
  const uint32_t status = FDCAN_TXFQS;
  if ((status & TXFQS_FULL) != 0u) {
    return false;
  }
  const uint32_t index = (status >> TXFQS_PUT_SHIFT) & TXFQS_INDEX_MASK;
  const uint32_t offset = g4_fdcan_ram_tx_buffer_offset(index);
  uint32_t words[G4_FDCAN_RAM_FRAME_WORDS];
  g4_fdcan_ram_pack_tx(frame, words);
  for (uint32_t i = 0u; i < G4_FDCAN_RAM_FRAME_WORDS; i++) {
    FDCAN_RAM(offset + 4u * i) = words[i];
  }
  FDCAN_TXBAR = 1u << index;
  return true;
}

void g4_fdcan_acknowledge(g4_fdcan_t *const can) {
  const uint32_t flags = FDCAN_IR & IR_HANDLED;
  FDCAN_IR = flags; /* write 1 to clear */
  if ((flags & IR_RF0L) != 0u) {
    can->rx_lost++;
  }
}

bool g4_fdcan_receive(g4_fdcan_t *const can, can_frame_t *const frame, uint32_t *const rx_time_us) {
  for (;;) {
    const uint32_t status = FDCAN_RXF0S;
    if ((status & RXF0S_FILL_MASK) == 0u) {
      return false;
    }
    const uint32_t index = (status >> RXF0S_GET_SHIFT) & RXF0S_INDEX_MASK;
    const uint32_t offset = g4_fdcan_ram_rx_fifo0_offset(index);
    uint32_t words[G4_FDCAN_RAM_FRAME_WORDS];
    for (uint32_t i = 0u; i < G4_FDCAN_RAM_FRAME_WORDS; i++) {
      words[i] = FDCAN_RAM(offset + 4u * i);
    }
    const uint32_t now_us = g4_timer_now_us();
    const uint16_t now_stamp = (uint16_t)FDCAN_TSCV;
    FDCAN_RXF0A = index;
    uint16_t stamp;
    if (g4_fdcan_ram_unpack_rx(words, frame, &stamp)) {
      *rx_time_us = can->frame_stamps ? g4_fdcan_ram_rx_time_us(now_us, now_stamp, stamp) : now_us;
      return true;
    }
    can->rx_rejected++;
  }
}

void g4_fdcan_service(g4_fdcan_t *const can) {
  if ((FDCAN_CCCR & CCCR_INIT) != 0u && (FDCAN_PSR & PSR_BO) != 0u) {
    can->bus_off++;
    FDCAN_CCCR &= ~CCCR_INIT;
  }
}
