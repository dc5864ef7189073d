/* The lm3s6965evb's external interrupts: UART0 receives SLCAN; every other one ends the run. */
#include "lm3s6965.h"
#include "startup.h"

void board_uart0_handler(void);

#define DEFAULT_4 board_default_handler, board_default_handler, board_default_handler, \
                  board_default_handler

BOARD_IRQ_VECTORS const board_handler_t board_irq_vectors[LM3S_IRQS] = {
    board_default_handler, board_default_handler, board_default_handler, /* GPIO A-C */
    board_default_handler, board_default_handler,                        /* GPIO D-E */
    board_uart0_handler,                                                 /* 5: UART0 */
    board_default_handler,                                               /* 6: UART1 */
    board_default_handler,                                               /* 7: SSI0 */
    DEFAULT_4, DEFAULT_4, DEFAULT_4, DEFAULT_4, DEFAULT_4,               /* 8-27 */
    DEFAULT_4, DEFAULT_4, DEFAULT_4, DEFAULT_4, DEFAULT_4,               /* 28-47 */
};
