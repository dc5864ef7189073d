/* Clock tree set-up (g4_clock.h). Polls are bounded by loop counts: no timer runs yet. */
#include "g4_clock.h"

#include "g4_regs.h"

#define RCC_CR_HSION (1u << 8)
#define RCC_CR_HSIRDY (1u << 10)
#define RCC_CR_HSEON (1u << 16)
#define RCC_CR_HSERDY (1u << 17)
#define RCC_CR_CSSON (1u << 19)
#define RCC_CR_PLLON (1u << 24)
#define RCC_CR_PLLRDY (1u << 25)
#define RCC_CFGR_SW_MASK 0x3u
#define RCC_CFGR_SW_PLL 0x3u
#define RCC_CFGR_SWS_SHIFT 2u
#define RCC_CFGR_HPRE_MASK (0xFu << 4)
#define RCC_CFGR_HPRE_DIV2 (0x8u << 4)
#define RCC_CFGR_PPRE_MASK ((0x7u << 8) | (0x7u << 11)) /* APB1, APB2: 0 = undivided */
#define RCC_PLLCFGR_SRC_HSI16 0x2u
#define RCC_PLLCFGR_SRC_HSE 0x3u
#define RCC_PLLCFGR_M_SHIFT 4u
#define RCC_PLLCFGR_N_SHIFT 8u
#define RCC_PLLCFGR_REN (1u << 24)
#define RCC_PLLCFGR_R_SHIFT 25u /* 0: /2, 1: /4, 2: /6, 3: /8 */
#define PWR_CR3_UCPD_DBDIS (1u << 14)
#define PWR_CR5_R1MODE (1u << 8) /* 1: range 1 normal, 0: range 1 boost */
#define PWR_SR2_VOSF (1u << 10)
#define FLASH_ACR G4_REG(G4_FLASH_IF_BASE + 0x00u)
#define FLASH_ACR_LATENCY_MASK 0xFu
#define FLASH_ACR_PRFTEN (1u << 8)
#define FLASH_ACR_ICEN (1u << 9)
#define FLASH_ACR_DCEN (1u << 10)

#define HSE_START_POLLS 200000u /* > 20 ms at 16 MHz: crystals start in about 2 ms */
#define READY_POLLS 100000u
#define AHB_SETTLE_LOOPS 200u   /* > 1 us at 85 MHz (HCLK / 2) */

/* Waits until (register & mask) == value, at most `polls` reads. */
static bool g4_clock_wait(volatile uint32_t *const reg, uint32_t mask, uint32_t value,
                          uint32_t polls) {
  for (uint32_t i = 0u; i < polls; i++) {
    if ((*reg & mask) == value) {
      return true;
    }
  }
  return false;
}

static bool g4_clock_start_crystal(void) {
  G4_RCC_CR |= RCC_CR_HSEON;
  if (g4_clock_wait(&G4_RCC_CR, RCC_CR_HSERDY, RCC_CR_HSERDY, HSE_START_POLLS)) {
    return true;
  }
  G4_RCC_CR &= ~RCC_CR_HSEON;
  return false;
}

static bool g4_clock_start_pll(uint32_t source) {
  G4_RCC_PLLCFGR = source | ((G4_CLOCK_PLL_M - 1u) << RCC_PLLCFGR_M_SHIFT) |
                   (G4_CLOCK_PLL_N << RCC_PLLCFGR_N_SHIFT) |
                   ((G4_CLOCK_PLL_R / 2u - 1u) << RCC_PLLCFGR_R_SHIFT) | RCC_PLLCFGR_REN;
  G4_RCC_CR |= RCC_CR_PLLON;
  return g4_clock_wait(&G4_RCC_CR, RCC_CR_PLLRDY, RCC_CR_PLLRDY, READY_POLLS);
}

/* RM0440 "range 1 normal to range 1 boost": HCLK / 2, boost, wait states, switch, 1 us,
 * HCLK / 1. */
static bool g4_clock_switch_to_pll(void) {
  G4_RCC_CFGR = (G4_RCC_CFGR & ~(RCC_CFGR_HPRE_MASK | RCC_CFGR_PPRE_MASK)) | RCC_CFGR_HPRE_DIV2;
  G4_PWR_CR5 &= ~PWR_CR5_R1MODE;
  (void)g4_clock_wait(&G4_PWR_SR2, PWR_SR2_VOSF, 0u, READY_POLLS);
  FLASH_ACR = (FLASH_ACR & ~FLASH_ACR_LATENCY_MASK) | G4_CLOCK_FLASH_WAIT_STATES |
              FLASH_ACR_PRFTEN | FLASH_ACR_ICEN | FLASH_ACR_DCEN;
  if (!g4_clock_wait(&FLASH_ACR, FLASH_ACR_LATENCY_MASK, G4_CLOCK_FLASH_WAIT_STATES, READY_POLLS)) {
    return false;
  }
  G4_RCC_CFGR = (G4_RCC_CFGR & ~RCC_CFGR_SW_MASK) | RCC_CFGR_SW_PLL;
  if (!g4_clock_wait(&G4_RCC_CFGR, RCC_CFGR_SW_MASK << RCC_CFGR_SWS_SHIFT,
                     RCC_CFGR_SW_PLL << RCC_CFGR_SWS_SHIFT, READY_POLLS)) {
    return false;
  }
  for (volatile uint32_t i = 0u; i < AHB_SETTLE_LOOPS; i++) {
  }
  G4_RCC_CFGR &= ~RCC_CFGR_HPRE_MASK;
  return true;
}

g4_clock_source_t g4_clock_init(void) {
  G4_RCC_APB1ENR1 |= G4_RCC_APB1ENR1_PWR;
  G4_RCC_APB2ENR |= G4_RCC_APB2ENR_SYSCFG;
  (void)G4_RCC_APB1ENR1; /* the clock is on once the write has completed */
  G4_PWR_CR3 |= PWR_CR3_UCPD_DBDIS; /* no USB-C dead-battery pull-downs on PB4/PB6 */
  G4_RCC_CR |= RCC_CR_HSION;
  (void)g4_clock_wait(&G4_RCC_CR, RCC_CR_HSIRDY, RCC_CR_HSIRDY, READY_POLLS);
  const bool crystal = g4_clock_start_crystal();
  if (!g4_clock_start_pll(crystal ? RCC_PLLCFGR_SRC_HSE : RCC_PLLCFGR_SRC_HSI16) ||
      !g4_clock_switch_to_pll()) {
    return G4_CLOCK_FAILED;
  }
  if (crystal) {
    G4_RCC_CR |= RCC_CR_CSSON;
  }
  return crystal ? G4_CLOCK_CRYSTAL : G4_CLOCK_INTERNAL;
}
