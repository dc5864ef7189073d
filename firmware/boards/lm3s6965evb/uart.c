/* UART0 (SLCAN, interrupt-driven receive) and UART1 (log) of the lm3s6965evb (board.h). */
#include <stdint.h>

#include "board.h"
#include "cortex_m.h"
#include "lm3s6965.h"

#define RX_RING_SIZE 512u /* characters; a power of two */
#define BAUD_HZ 115200u

/* Single producer (the UART0 interrupt), single consumer (the main loop). */
static board_rx_t rx_ring[RX_RING_SIZE];
static volatile uint32_t rx_head; /* written by the interrupt only */
static volatile uint32_t rx_tail; /* written by the main loop only */
static volatile uint32_t rx_overruns;

static void uart_configure(uint32_t uart, bool receive_interrupt) {
  /* Baud divisor BOARD_CPU_HZ / (16 * BAUD_HZ) in 64ths, rounded: 27 + 8/64. */
  const uint32_t divisor_64ths = (BOARD_CPU_HZ * 8u / BAUD_HZ + 1u) / 2u;
  UART_CTL(uart) = 0u;
  UART_IBRD(uart) = divisor_64ths / 64u;
  UART_FBRD(uart) = divisor_64ths % 64u;
  UART_LCRH(uart) = UART_LCRH_WLEN_8 | UART_LCRH_FEN;
  UART_IM(uart) = receive_interrupt ? (UART_INT_RX | UART_INT_RT) : 0u;
  UART_CTL(uart) = UART_CTL_UARTEN | UART_CTL_TXE | UART_CTL_RXE;
}

void board_uart_init(void) {
  SYSCTL_RCGC1 |= SYSCTL_RCGC1_UART0 | SYSCTL_RCGC1_UART1;
  SYSCTL_RCGC2 |= SYSCTL_RCGC2_GPIOA | SYSCTL_RCGC2_GPIOD;
  GPIO_AFSEL(GPIO_PORTA) |= 0x03u; /* PA0 U0Rx, PA1 U0Tx */
  GPIO_DEN(GPIO_PORTA) |= 0x03u;
  GPIO_AFSEL(GPIO_PORTD) |= 0x0Cu; /* PD2 U1Rx, PD3 U1Tx */
  GPIO_DEN(GPIO_PORTD) |= 0x0Cu;
  uart_configure(UART0, true);
  uart_configure(UART1, false);
  cortex_m_irq_enable(UART0_IRQ);
}

void board_uart0_handler(void) {
  UART_ICR(UART0) = UART_INT_RX | UART_INT_RT;
  const uint32_t now_us = board_now_us();
  while ((UART_FR(UART0) & UART_FR_RXFE) == 0u) {
    const char character = (char)(UART_DR(UART0) & 0xFFu);
    const uint32_t head = rx_head;
    if (head - rx_tail >= RX_RING_SIZE) {
      rx_overruns = rx_overruns + 1u;
      continue;
    }
    rx_ring[head % RX_RING_SIZE] = (board_rx_t){.character = character, .time_us = now_us};
    rx_head = head + 1u;
  }
}

bool board_uart0_receive(board_rx_t *const received) {
  const uint32_t tail = rx_tail;
  if (tail == rx_head) {
    return false;
  }
  *received = rx_ring[tail % RX_RING_SIZE];
  rx_tail = tail + 1u;
  return true;
}

uint32_t board_uart0_overruns(void) { return rx_overruns; }

static void uart_write(uint32_t uart, const char *data, size_t length) {
  for (size_t i = 0u; i < length; i++) {
    while ((UART_FR(uart) & UART_FR_TXFF) != 0u) {
    }
    UART_DR(uart) = (uint8_t)data[i];
  }
}

void board_uart0_write(const char *data, size_t length) { uart_write(UART0, data, length); }
void board_uart1_write(const char *data, size_t length) { uart_write(UART1, data, length); }

void board_uart1_write_text(const char *text) {
  size_t length = 0u;
  while (text[length] != '\0') {
    length++;
  }
  board_uart1_write(text, length);
}
