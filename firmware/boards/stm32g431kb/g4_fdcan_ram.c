/* FDCAN message RAM layout and elements (g4_fdcan_ram.h). */
#include "g4_fdcan_ram.h"

/* Element header fields (RM0440, Rx and Tx buffer elements). */
#define ELEMENT_XTD (1u << 30)
#define ELEMENT_RTR (1u << 29)
#define ELEMENT_STD_ID_SHIFT 18u
#define ELEMENT_STD_ID_MASK 0x7FFu
#define ELEMENT_FDF (1u << 21)
#define ELEMENT_DLC_SHIFT 16u
#define ELEMENT_DLC_MASK 0xFu
#define ELEMENT_RXTS_MASK 0xFFFFu

/* Standard filter element fields. */
#define FILTER_SFT_DUAL (1u << 30)      /* SFT = 01: match SFID1 or SFID2 */
#define FILTER_SFEC_FIFO0 (1u << 27)    /* SFEC = 001: store in receive FIFO 0 */
#define FILTER_SFID1_SHIFT 16u

uint32_t g4_fdcan_ram_rx_fifo0_offset(uint32_t index) {
  return G4_FDCAN_RAM_RX_FIFO0_OFFSET + index * G4_FDCAN_RAM_ELEMENT_BYTES;
}

uint32_t g4_fdcan_ram_tx_buffer_offset(uint32_t index) {
  return G4_FDCAN_RAM_TX_BUFFER_OFFSET + index * G4_FDCAN_RAM_ELEMENT_BYTES;
}

uint32_t g4_fdcan_ram_filter_dual_to_fifo0(uint16_t id1, uint16_t id2) {
  return FILTER_SFT_DUAL | FILTER_SFEC_FIFO0 |
         ((uint32_t)(id1 & ELEMENT_STD_ID_MASK) << FILTER_SFID1_SHIFT) |
         (uint32_t)(id2 & ELEMENT_STD_ID_MASK);
}

static uint32_t g4_fdcan_ram_data_word(const uint8_t *const bytes) {
  return (uint32_t)bytes[0] | ((uint32_t)bytes[1] << 8) | ((uint32_t)bytes[2] << 16) |
         ((uint32_t)bytes[3] << 24);
}

void g4_fdcan_ram_pack_tx(const can_frame_t *const frame,
                          uint32_t words[G4_FDCAN_RAM_FRAME_WORDS]) {
  uint8_t data[CAN_FRAME_MAX_DATA] = {0};
  const uint8_t length = frame->length <= CAN_FRAME_MAX_DATA ? frame->length : CAN_FRAME_MAX_DATA;
  for (uint8_t i = 0u; i < length; i++) {
    data[i] = frame->data[i];
  }
  words[0] = (uint32_t)(frame->id & ELEMENT_STD_ID_MASK) << ELEMENT_STD_ID_SHIFT;
  words[1] = (uint32_t)length << ELEMENT_DLC_SHIFT; /* classic, no event, no marker */
  words[2] = g4_fdcan_ram_data_word(&data[0]);
  words[3] = g4_fdcan_ram_data_word(&data[4]);
}

bool g4_fdcan_ram_unpack_rx(const uint32_t words[G4_FDCAN_RAM_FRAME_WORDS],
                            can_frame_t *const frame, uint16_t *const timestamp) {
  if ((words[0] & (ELEMENT_XTD | ELEMENT_RTR)) != 0u || (words[1] & ELEMENT_FDF) != 0u) {
    return false;
  }
  const uint32_t dlc = (words[1] >> ELEMENT_DLC_SHIFT) & ELEMENT_DLC_MASK;
  frame->id = (uint16_t)((words[0] >> ELEMENT_STD_ID_SHIFT) & ELEMENT_STD_ID_MASK);
  frame->length = (uint8_t)(dlc < CAN_FRAME_MAX_DATA ? dlc : CAN_FRAME_MAX_DATA);
  for (uint8_t i = 0u; i < CAN_FRAME_MAX_DATA; i++) {
    frame->data[i] = (uint8_t)(words[2u + i / 4u] >> (8u * (i % 4u)));
  }
  *timestamp = (uint16_t)(words[1] & ELEMENT_RXTS_MASK);
  return true;
}

uint32_t g4_fdcan_ram_rx_time_us(uint32_t now_us, uint16_t now_stamp, uint16_t rx_stamp) {
  const uint16_t age_us = (uint16_t)(now_stamp - rx_stamp);
  return now_us - age_us;
}
