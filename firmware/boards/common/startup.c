/* Cortex-M start-up shared by the boards (startup.h). */
#include "startup.h"

#include <stdint.h>

#include "cortex_m.h"
#include "semihosting.h"

/* Symbols of the linker script (sections.ld). */
extern uint32_t board_data_load[];
extern uint32_t board_data_start[];
extern uint32_t board_data_end[];
extern uint32_t board_bss_start[];
extern uint32_t board_bss_end[];
extern uint32_t board_stack_top[];

void board_reset_handler(void);

void board_default_handler(void) { semihosting_exit(BOARD_EXIT_FAULT); }

void board_systick_handler(void) __attribute__((weak, alias("board_default_handler")));

typedef struct {
  uint32_t *initial_stack;
  board_handler_t handlers[15];
} board_core_vectors_t;

__attribute__((section(".vectors.core"), used))
const board_core_vectors_t board_core_vectors = {
    .initial_stack = board_stack_top,
    .handlers = {
        board_reset_handler,
        board_default_handler, /* NMI */
        board_default_handler, /* HardFault */
        board_default_handler, /* MemManage */
        board_default_handler, /* BusFault */
        board_default_handler, /* UsageFault */
        0, 0, 0, 0,            /* reserved */
        board_default_handler, /* SVCall */
        board_default_handler, /* DebugMonitor */
        0,                     /* reserved */
        board_default_handler, /* PendSV */
        board_systick_handler,
    },
};

/* Word loops: no library call before .data and .bss exist. */
__attribute__((optimize("no-tree-loop-distribute-patterns")))
static void init_memory(void) {
  const uint32_t *source = board_data_load;
  for (uint32_t *word = board_data_start; word < board_data_end; word++) {
    *word = *source++;
  }
  for (uint32_t *word = board_bss_start; word < board_bss_end; word++) {
    *word = 0u;
  }
}

void board_reset_handler(void) {
  init_memory();
#if defined(__ARM_FP)
  SCB_CPACR |= 0xFu << 20; /* CP10 and CP11 (the FPU): full access */
  __asm__ volatile("dsb\n\tisb" ::: "memory");
#endif
  semihosting_exit(main());
}
