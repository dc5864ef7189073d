/* Clock and microsecond timer of the lm3s6965evb (board.h).
 *
 * The timer is SysTick on the core clock, interrupting every millisecond, plus the
 * ticks elapsed in the current millisecond. (The general-purpose timers would serve on
 * the chip, but QEMU 7.2's model of them cannot be read back: GPTM TAR reads 0.) */
#include <stdint.h>

#include "board.h"
#include "cortex_m.h"
#include "lm3s6965.h"

#define TICKS_PER_US (BOARD_CPU_HZ / 1000000u)
#define TICKS_PER_MS (BOARD_CPU_HZ / 1000u)

static volatile uint32_t elapsed_ms;

void board_systick_handler(void) { elapsed_ms = elapsed_ms + 1u; }

static void clock_init(void) {
  uint32_t rcc = SYSCTL_RCC;
  rcc |= SYSCTL_RCC_BYPASS;
  rcc &= ~SYSCTL_RCC_USESYSDIV;
  SYSCTL_RCC = rcc;
  rcc &= ~(SYSCTL_RCC_XTAL_MASK | SYSCTL_RCC_OSCSRC_MASK | SYSCTL_RCC_PWRDN |
           SYSCTL_RCC_SYSDIV_MASK);
  rcc |= SYSCTL_RCC_XTAL_8MHZ | SYSCTL_RCC_SYSDIV(4u) | SYSCTL_RCC_USESYSDIV;
  SYSCTL_RCC = rcc;
  for (uint32_t spins = 0u; (SYSCTL_RIS & SYSCTL_RIS_PLLLRIS) == 0u && spins < 100000u; spins++) {
  }
  SYSCTL_RCC = rcc & ~SYSCTL_RCC_BYPASS;
}

static void timer_init(void) {
  SYST_RVR = TICKS_PER_MS - 1u;
  SYST_CVR = 0u;
  SYST_CSR = SYST_CSR_ENABLE | SYST_CSR_TICKINT | SYST_CSR_CLKSOURCE_CORE;
}

void board_init(void) {
  clock_init();
  timer_init();
  board_uart_init();
  cortex_m_interrupts_enable();
}

/* A wrap pending but not yet counted (read from an interrupt of equal or higher
 * priority, or with interrupts off) is added here; the current value is then read
 * again so that it is certainly after the wrap. */
uint32_t board_now_us(void) {
  uint32_t ms;
  uint32_t ticks;
  bool pending;
  do {
    ms = elapsed_ms;
    ticks = TICKS_PER_MS - 1u - SYST_CVR;
    pending = (SCB_ICSR & SCB_ICSR_PENDSTSET) != 0u;
    if (pending) {
      ticks = TICKS_PER_MS - 1u - SYST_CVR;
    }
  } while (ms != elapsed_ms);
  return (ms + (pending ? 1u : 0u)) * 1000u + ticks / TICKS_PER_US;
}

void board_delay_us(uint32_t microseconds) {
  const uint32_t start = board_now_us();
  while (board_now_us() - start < microseconds) {
  }
}
