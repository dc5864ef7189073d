/* The lm3s6965evb board (QEMU's model of TI's LM3S6965 evaluation board, Cortex-M3):
 * clock, microsecond timer, UARTs and the I2C master as a bus_t. */
#ifndef FIRMWARE_BOARDS_LM3S6965EVB_BOARD_H
#define FIRMWARE_BOARDS_LM3S6965EVB_BOARD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "bus.h"

#define BOARD_CPU_HZ 50000000u /* PLL 200 MHz / 4 from the 8 MHz crystal */

/* PLL on, core at BOARD_CPU_HZ; the microsecond timer running; interrupts on. */
void board_init(void);

/* Free-running microsecond timer (wraps at 2^32 us). Callable from interrupts. */
uint32_t board_now_us(void);
void board_delay_us(uint32_t microseconds);

/* UART0 (the SLCAN line): 8N1, receive interrupt into a ring buffer. UART1 (the log):
 * transmit only. QEMU's `-serial` options attach them in that order. */
typedef struct {
  char character;
  uint32_t time_us; /* when the receive interrupt took it */
} board_rx_t;

void board_uart_init(void);
void board_uart0_write(const char *data, size_t length);
void board_uart1_write(const char *data, size_t length);
void board_uart1_write_text(const char *text);
/* The oldest character received on UART0; false when none is waiting. */
bool board_uart0_receive(board_rx_t *const received);
/* Characters lost because the ring buffer was full, since start-up. */
uint32_t board_uart0_overruns(void);

/* The I2C0 master (PB2 SCL, PB3 SDA) at 400 kHz, as a bus_t. A register read is two
 * transfers: the register pointer written (START ... STOP), then a new read. */
void board_i2c_init(bus_t *const bus);

#endif /* FIRMWARE_BOARDS_LM3S6965EVB_BOARD_H */
