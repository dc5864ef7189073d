/* TIM2 as the microsecond clock, INT1 capture and tick (g4_timer.h). */
#include "g4_timer.h"

#include "g4_regs.h"

#define TIM2_CR1 G4_REG(G4_TIM2_BASE + 0x00u)
#define TIM2_DIER G4_REG(G4_TIM2_BASE + 0x0Cu)
#define TIM2_SR G4_REG(G4_TIM2_BASE + 0x10u)
#define TIM2_EGR G4_REG(G4_TIM2_BASE + 0x14u)
#define TIM2_CCMR1 G4_REG(G4_TIM2_BASE + 0x18u)
#define TIM2_CCER G4_REG(G4_TIM2_BASE + 0x20u)
#define TIM2_CNT G4_REG(G4_TIM2_BASE + 0x24u)
#define TIM2_PSC G4_REG(G4_TIM2_BASE + 0x28u)
#define TIM2_ARR G4_REG(G4_TIM2_BASE + 0x2Cu)
#define TIM2_CCR1 G4_REG(G4_TIM2_BASE + 0x34u)
#define TIM2_CCR2 G4_REG(G4_TIM2_BASE + 0x38u)

#define TIM_CR1_CEN (1u << 0)
#define TIM_DIER_CC1IE (1u << 1)
#define TIM_DIER_CC2IE (1u << 2)
#define TIM_SR_CC1IF (1u << 1)
#define TIM_SR_CC2IF (1u << 2)
#define TIM_SR_CC1OF (1u << 9)
#define TIM_EGR_UG (1u << 0)
#define TIM_CCMR1_CC1S_TI1 (1u << 0)   /* channel 1 input, from its own pin */
#define TIM_CCMR1_IC1F_N8 (3u << 4)    /* 8 samples at the timer clock */
#define TIM_CCER_CC1E (1u << 0)        /* capture on; CC1P = CC1NP = 0: rising edge */

void g4_timer_init(uint32_t timer_clock_hz) {
  G4_RCC_APB1ENR1 |= G4_RCC_APB1ENR1_TIM2;
  (void)G4_RCC_APB1ENR1;
  TIM2_CR1 = 0u;
  TIM2_PSC = timer_clock_hz / G4_TIMER_HZ - 1u;
  TIM2_ARR = 0xFFFFFFFFu;
  TIM2_CCMR1 = TIM_CCMR1_CC1S_TI1 | TIM_CCMR1_IC1F_N8; /* channel 2: frozen output compare */
  TIM2_CCER = TIM_CCER_CC1E;
  TIM2_EGR = TIM_EGR_UG; /* loads the prescaler, counter at 0 */
  TIM2_CCR2 = G4_TIMER_TICK_US;
  TIM2_SR = 0u;
  TIM2_DIER = TIM_DIER_CC1IE | TIM_DIER_CC2IE;
  TIM2_CR1 = TIM_CR1_CEN;
}

uint32_t g4_timer_now_us(void) { return TIM2_CNT; }

void g4_timer_delay_us(uint32_t microseconds) {
  const uint32_t start = TIM2_CNT;
  while (TIM2_CNT - start <= microseconds) {
  }
}

/* The next tick 1 ms after the last one, or after now if the interrupt came that late
 * (a compare value already passed would only match again after the counter wraps). */
static void g4_timer_schedule_tick(void) {
  const uint32_t now = TIM2_CNT;
  uint32_t next = TIM2_CCR2 + G4_TIMER_TICK_US;
  if ((int32_t)(next - now) < 2) {
    next = now + G4_TIMER_TICK_US;
  }
  TIM2_CCR2 = next;
}

g4_timer_events_t g4_timer_service(void) {
  g4_timer_events_t events = {0};
  const uint32_t status = TIM2_SR;
  uint32_t clear = 0u;
  if ((status & TIM_SR_CC1IF) != 0u) {
    events.captured = true;
    events.capture_us = TIM2_CCR1; /* reading clears CC1IF */
    events.capture_missed = (status & TIM_SR_CC1OF) != 0u;
    clear |= TIM_SR_CC1OF;
  }
  if ((status & TIM_SR_CC2IF) != 0u) {
    events.tick = true;
    g4_timer_schedule_tick();
    clear |= TIM_SR_CC2IF;
  }
  TIM2_SR = ~clear; /* rc_w0: zeros clear, ones leave flags alone */
  return events;
}
