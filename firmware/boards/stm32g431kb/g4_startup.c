/* Vector table, reset and fault handlers (g4_startup.h). */
#include "g4_startup.h"

/* Symbols of the linker script (stm32g431kb.ld). */
extern uint32_t g4_data_load[];
extern uint32_t g4_data_start[];
extern uint32_t g4_data_end[];
extern uint32_t g4_bss_start[];
extern uint32_t g4_bss_end[];
extern uint32_t g4_stack_bottom[];
extern uint32_t g4_stack_top[];

#define CPACR_CP10_CP11_FULL (0xFu << 20)
#define MPU_RBAR_VALID (1u << 4)           /* region number taken from RBAR[3:0] = 0 */
#define MPU_RASR_ENABLE (1u << 0)
#define MPU_RASR_SIZE_32_BYTES (4u << 1)   /* 2^(4 + 1) */
#define MPU_RASR_XN (1u << 28)             /* AP = 000: no access at all */
#define MPU_CTRL_ENABLE (1u << 0)
#define MPU_CTRL_PRIVDEFENA (1u << 2)      /* the default map everywhere else */

void g4_fault_handler(void) { g4_system_reset(); }

void g4_default_handler(void) { g4_system_reset(); }

#define D g4_default_handler
#define D10 D, D, D, D, D, D, D, D, D, D

__attribute__((section(".isr_vector"), used))
const g4_vector_table_t g4_vector_table = {
    .initial_stack = g4_stack_top,
    .core =
        {
            g4_reset_handler,
            g4_fault_handler, /* NMI: clock security system */
            g4_fault_handler, /* HardFault */
            g4_fault_handler, /* MemManage: the stack guard */
            g4_fault_handler, /* BusFault */
            g4_fault_handler, /* UsageFault */
            0, 0, 0, 0,       /* reserved */
            D,                /* SVCall */
            D,                /* DebugMonitor */
            0,                /* reserved */
            D,                /* PendSV */
            D,                /* SysTick */
        },
    .irq =
        {
            D10, D10,             /* 0 WWDG .. 19 USB_HP */
            D,                    /* 20 USB_LP */
            board_fdcan1_it0_isr, /* 21 FDCAN1_IT0 */
            D, D, D, D, D, D,     /* 22 FDCAN1_IT1 .. 27 TIM1_CC */
            board_tim2_isr,       /* 28 TIM2 */
            D,                    /* 29 TIM3 */
            D10, D10, D10, D10, D10, D10, D10, /* 30 TIM4 .. 99 */
            D, D,                 /* 100 CORDIC, 101 FMAC */
        },
};

/* Word loops, not memcpy/memset: nothing is called before memory exists. */
__attribute__((optimize("no-tree-loop-distribute-patterns")))
static void g4_startup_memory(void) {
  const uint32_t *source = g4_data_load;
  for (uint32_t *word = g4_data_start; word < g4_data_end; word++) {
    *word = *source++;
  }
  for (uint32_t *word = g4_bss_start; word < g4_bss_end; word++) {
    *word = 0u;
  }
}

static void g4_startup_stack_guard(void) {
  G4_MPU_RNR = 0u;
  G4_MPU_RBAR = (uint32_t)(uintptr_t)g4_stack_bottom | MPU_RBAR_VALID;
  G4_MPU_RASR = MPU_RASR_XN | MPU_RASR_SIZE_32_BYTES | MPU_RASR_ENABLE;
  G4_MPU_CTRL = MPU_CTRL_PRIVDEFENA | MPU_CTRL_ENABLE;
  g4_barrier();
}

void g4_reset_handler(void) {
  G4_SCB_CPACR |= CPACR_CP10_CP11_FULL;
  g4_barrier();
  g4_startup_memory();
  G4_SCB_VTOR = (uint32_t)(uintptr_t)&g4_vector_table;
  g4_startup_stack_guard();
  board_main();
}
