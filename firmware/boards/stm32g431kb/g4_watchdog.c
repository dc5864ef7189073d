/* Independent watchdog (g4_watchdog.h). */
#include "g4_watchdog.h"

#include "g4_regs.h"

#define IWDG_KR G4_REG(G4_IWDG_BASE + 0x00u)
#define IWDG_PR G4_REG(G4_IWDG_BASE + 0x04u)
#define IWDG_RLR G4_REG(G4_IWDG_BASE + 0x08u)
#define IWDG_SR G4_REG(G4_IWDG_BASE + 0x0Cu)
#define IWDG_KEY_START 0xCCCCu
#define IWDG_KEY_UNLOCK 0x5555u
#define IWDG_KEY_REFRESH 0xAAAAu
#define IWDG_PRESCALER_MAX_CODE 6u /* divider 4 << code: 4 .. 256 */
#define IWDG_RELOAD_MAX 0xFFFu
#define IWDG_UPDATE_POLLS 100000u  /* the update takes a few LSI periods (~ 200 us) */

bool g4_watchdog_start(uint32_t timeout_ms) {
  uint32_t code = 0u;
  uint32_t reload = 0u;
  for (; code <= IWDG_PRESCALER_MAX_CODE; code++) {
    const uint32_t divider = 4u << code;
    reload = timeout_ms * (G4_WATCHDOG_LSI_HZ / 1000u) / divider;
    if (reload <= IWDG_RELOAD_MAX + 1u) {
      break;
    }
  }
  if (timeout_ms > G4_WATCHDOG_TIMEOUT_MAX_MS || code > IWDG_PRESCALER_MAX_CODE || reload == 0u) {
    return false;
  }
  G4_DBGMCU_APB1FZR1 |= G4_DBGMCU_APB1FZR1_IWDG;
  IWDG_KR = IWDG_KEY_START;
  IWDG_KR = IWDG_KEY_UNLOCK;
  IWDG_PR = code;
  IWDG_RLR = reload - 1u;
  uint32_t polls = 0u;
  while (IWDG_SR != 0u && polls < IWDG_UPDATE_POLLS) {
    polls++;
  }
  IWDG_KR = IWDG_KEY_REFRESH;
  return polls < IWDG_UPDATE_POLLS;
}

void g4_watchdog_refresh(void) { IWDG_KR = IWDG_KEY_REFRESH; }
