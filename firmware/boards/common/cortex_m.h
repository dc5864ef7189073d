/* The Cortex-M3/M4 core registers the boards use (SysTick, NVIC, SCB), by address:
 * the ARMv7-M architecture fixes them, whatever the vendor. */
#ifndef FIRMWARE_BOARDS_COMMON_CORTEX_M_H
#define FIRMWARE_BOARDS_COMMON_CORTEX_M_H

#include <stdint.h>

#define CORTEX_M_REG(address) (*(volatile uint32_t *)(address))

/* SysTick: a 24-bit down-counter on the core clock. */
#define SYST_CSR CORTEX_M_REG(0xE000E010u)
#define SYST_RVR CORTEX_M_REG(0xE000E014u)
#define SYST_CVR CORTEX_M_REG(0xE000E018u)
#define SYST_CSR_ENABLE (1u << 0)
#define SYST_CSR_TICKINT (1u << 1)
#define SYST_CSR_CLKSOURCE_CORE (1u << 2)
#define SYST_MAX_RELOAD 0x00FFFFFFu

/* NVIC: enable and priority of the external interrupts. */
#define NVIC_ISER(n) CORTEX_M_REG(0xE000E100u + 4u * (n))
#define NVIC_IPR_BYTE(irq) (*(volatile uint8_t *)(0xE000E400u + (irq)))

/* SCB: pending SysTick, coprocessor access (the FPU). */
#define SCB_ICSR CORTEX_M_REG(0xE000ED04u)
#define SCB_ICSR_PENDSTSET (1u << 26)
#define SCB_CPACR CORTEX_M_REG(0xE000ED88u)

static inline void cortex_m_irq_enable(unsigned irq) {
  NVIC_ISER(irq / 32u) = 1u << (irq % 32u);
}

static inline void cortex_m_interrupts_enable(void) { __asm__ volatile("cpsie i" ::: "memory"); }
static inline void cortex_m_interrupts_disable(void) { __asm__ volatile("cpsid i" ::: "memory"); }
static inline void cortex_m_wait_for_interrupt(void) { __asm__ volatile("wfi" ::: "memory"); }

#endif /* FIRMWARE_BOARDS_COMMON_CORTEX_M_H */
