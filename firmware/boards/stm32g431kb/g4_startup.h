/* Start-up of the production node: the G431's vector table (16 core entries and its 102
 * interrupts, RM0440), the reset handler and the fault handlers.
 *
 * Reset: enables the FPU (before any float code), copies .data, zeroes .bss, points VTOR
 * at the table, arms a 32-byte no-access MPU region at the bottom of the stack (which the
 * linker script puts at the bottom of RAM) so an overflow faults instead of corrupting
 * data, then runs board_main. Every fault, the NMI (the clock security system's crystal
 * failure) and any interrupt without a handler reset the node; a fault while stacking
 * (the overflow itself) locks the core up, which the watchdog ends.
 *
 * This is not boards/common/startup.c: that one ends a QEMU run through semihosting on a
 * fault, which on a real node (no debugger) would itself fault.
 */
#ifndef FIRMWARE_BOARDS_STM32G431KB_G4_STARTUP_H
#define FIRMWARE_BOARDS_STM32G431KB_G4_STARTUP_H

#include <stdint.h>

#include "g4_regs.h"

typedef void (*g4_handler_t)(void);

typedef struct {
  uint32_t *initial_stack;
  g4_handler_t core[15];              /* reset .. SysTick */
  g4_handler_t irq[G4_IRQ_COUNT];     /* external interrupts 0..101 */
} g4_vector_table_t;

_Static_assert(sizeof(g4_vector_table_t) == (16u + G4_IRQ_COUNT) * 4u,
               "the vector table has 118 words");

#define G4_STACK_GUARD_BYTES 32u /* the MPU's smallest region */

__attribute__((noreturn)) void g4_reset_handler(void);
__attribute__((noreturn)) void g4_fault_handler(void);
__attribute__((noreturn)) void g4_default_handler(void);

/* The board's program and interrupt handlers (main.c). */
__attribute__((noreturn)) void board_main(void);
void board_tim2_isr(void);
void board_fdcan1_it0_isr(void);

#endif /* FIRMWARE_BOARDS_STM32G431KB_G4_STARTUP_H */
