/* Start-up shared by the Cortex-M boards: the core's part of the vector table, the reset
 * handler (copies .data, zeroes .bss, enables the FPU on an M4F, calls main, then ends
 * the QEMU run with main's return value through semihosting) and default handlers.
 *
 * A board adds its external interrupts as one array in section ".vectors.irq", which
 * the linker script (sections.ld) places right after the core's 16 entries:
 *   BOARD_IRQ_VECTORS const board_handler_t board_irq_vectors[N] = {...};
 */
#ifndef FIRMWARE_BOARDS_COMMON_STARTUP_H
#define FIRMWARE_BOARDS_COMMON_STARTUP_H

typedef void (*board_handler_t)(void);

#define BOARD_IRQ_VECTORS __attribute__((section(".vectors.irq"), used))

/* Exit code of a run that ended in a fault handler (HardFault and the like). */
#define BOARD_EXIT_FAULT 99

/* Any exception or interrupt without a handler of its own: ends the run. */
void board_default_handler(void);

/* Handlers a board may define (weak, default: board_default_handler). */
void board_systick_handler(void);

int main(void);

#endif /* FIRMWARE_BOARDS_COMMON_STARTUP_H */
