/* The STM32G431 registers this board uses, written by hand from the reference manual
 * (RM0440: memory map, RCC, PWR, FLASH, GPIO, SYSCFG) and the Cortex-M4 core's fixed
 * addresses. Each peripheral's own bits live in the file that drives it; this file has
 * the base addresses and the registers several files share (clock enables). */
#ifndef FIRMWARE_BOARDS_STM32G431KB_G4_REGS_H
#define FIRMWARE_BOARDS_STM32G431KB_G4_REGS_H

#include <stdint.h>

#define G4_REG(address) (*(volatile uint32_t *)(uintptr_t)(address))

/* Peripheral base addresses (RM0440 memory map). */
#define G4_TIM2_BASE 0x40000000u
#define G4_IWDG_BASE 0x40003000u
#define G4_I2C1_BASE 0x40005400u
#define G4_I2C2_BASE 0x40005800u
#define G4_FDCAN1_BASE 0x40006400u
#define G4_FDCAN_CONFIG_BASE 0x40006500u
#define G4_PWR_BASE 0x40007000u
#define G4_SRAMCAN_BASE 0x4000A400u
#define G4_SYSCFG_BASE 0x40010000u
#define G4_RCC_BASE 0x40021000u
#define G4_FLASH_IF_BASE 0x40022000u
#define G4_GPIOA_BASE 0x48000000u
#define G4_GPIOB_BASE 0x48000400u
#define G4_GPIOF_BASE 0x48001400u
#define G4_UID_BASE 0x1FFF7590u /* 96-bit unique device id, three words */
#define G4_DBGMCU_BASE 0xE0042000u

/* RCC: clock control, enables and kernel clock selection. */
#define G4_RCC_CR G4_REG(G4_RCC_BASE + 0x00u)
#define G4_RCC_CFGR G4_REG(G4_RCC_BASE + 0x08u)
#define G4_RCC_PLLCFGR G4_REG(G4_RCC_BASE + 0x0Cu)
#define G4_RCC_CICR G4_REG(G4_RCC_BASE + 0x20u)
#define G4_RCC_AHB2ENR G4_REG(G4_RCC_BASE + 0x4Cu)
#define G4_RCC_APB1ENR1 G4_REG(G4_RCC_BASE + 0x58u)
#define G4_RCC_APB2ENR G4_REG(G4_RCC_BASE + 0x60u)
#define G4_RCC_CCIPR G4_REG(G4_RCC_BASE + 0x88u)
#define G4_RCC_CSR G4_REG(G4_RCC_BASE + 0x94u)

#define G4_RCC_AHB2ENR_GPIOA (1u << 0)
#define G4_RCC_AHB2ENR_GPIOB (1u << 1)
#define G4_RCC_AHB2ENR_GPIOF (1u << 5)
#define G4_RCC_APB1ENR1_TIM2 (1u << 0)
#define G4_RCC_APB1ENR1_I2C1 (1u << 21)
#define G4_RCC_APB1ENR1_I2C2 (1u << 22)
#define G4_RCC_APB1ENR1_FDCAN (1u << 25)
#define G4_RCC_APB1ENR1_PWR (1u << 28)
#define G4_RCC_APB2ENR_SYSCFG (1u << 0)

/* Reset causes (RCC_CSR), cleared by writing RMVF. */
#define G4_RCC_CSR_RMVF (1u << 23)
#define G4_RCC_CSR_RESET_FLAGS 0xFE000000u /* OBL, PIN, BOR, SFT, IWDG, WWDG, LPWR */

/* PWR and SYSCFG registers used at start-up. */
#define G4_PWR_CR3 G4_REG(G4_PWR_BASE + 0x08u)
#define G4_PWR_SR2 G4_REG(G4_PWR_BASE + 0x14u)
#define G4_PWR_CR5 G4_REG(G4_PWR_BASE + 0x80u)
#define G4_SYSCFG_CFGR1 G4_REG(G4_SYSCFG_BASE + 0x04u)

/* Debug: stop the watchdog while a debugger halts the core. */
#define G4_DBGMCU_APB1FZR1 G4_REG(G4_DBGMCU_BASE + 0x08u)
#define G4_DBGMCU_APB1FZR1_IWDG (1u << 12)

/* Cortex-M4 system control block and MPU (ARMv7-M, fixed addresses). */
#define G4_SCB_VTOR G4_REG(0xE000ED08u)
#define G4_SCB_AIRCR G4_REG(0xE000ED0Cu)
#define G4_SCB_AIRCR_SYSRESETREQ 0x05FA0004u /* VECTKEY | SYSRESETREQ */
#define G4_SCB_CPACR G4_REG(0xE000ED88u)
#define G4_MPU_CTRL G4_REG(0xE000ED94u)
#define G4_MPU_RNR G4_REG(0xE000ED98u)
#define G4_MPU_RBAR G4_REG(0xE000ED9Cu)
#define G4_MPU_RASR G4_REG(0xE000EDA0u)
#define G4_NVIC_ISER(n) G4_REG(0xE000E100u + 4u * (n))
#define G4_NVIC_IPR_BYTE(irq) (*(volatile uint8_t *)(uintptr_t)(0xE000E400u + (irq)))
#define G4_NVIC_PRIORITY_BITS 4u /* the G4 implements 16 priority levels */

/* External interrupt numbers (RM0440 vector table) of the handlers this board has. */
#define G4_IRQ_FDCAN1_IT0 21u
#define G4_IRQ_TIM2 28u
#define G4_IRQ_COUNT 102u /* WWDG (0) .. FMAC (101) */

static inline void g4_irq_enable(uint32_t irq, uint32_t priority) {
  G4_NVIC_IPR_BYTE(irq) = (uint8_t)(priority << (8u - G4_NVIC_PRIORITY_BITS));
  G4_NVIC_ISER(irq / 32u) = 1u << (irq % 32u);
}

static inline void g4_interrupts_disable(void) { __asm__ volatile("cpsid i" ::: "memory"); }
static inline void g4_interrupts_enable(void) { __asm__ volatile("cpsie i" ::: "memory"); }
static inline void g4_wait_for_interrupt(void) { __asm__ volatile("wfi" ::: "memory"); }
static inline void g4_barrier(void) { __asm__ volatile("dsb\n\tisb" ::: "memory"); }

/* A software reset: the node starts again from its reset vector. */
__attribute__((noreturn)) static inline void g4_system_reset(void) {
  __asm__ volatile("dsb" ::: "memory");
  G4_SCB_AIRCR = G4_SCB_AIRCR_SYSRESETREQ;
  __asm__ volatile("dsb" ::: "memory");
  for (;;) {
  }
}

#endif /* FIRMWARE_BOARDS_STM32G431KB_G4_REGS_H */
