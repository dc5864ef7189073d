/* The independent watchdog (IWDG, clocked by the 32 kHz LSI, RM0440): once started it
 * cannot be stopped; the main loop refreshes it every pass, so a hang anywhere (a stuck
 * bus, a lockup after a double fault) resets the node within the timeout. It stops while
 * a debugger halts the core. */
#ifndef FIRMWARE_BOARDS_STM32G431KB_G4_WATCHDOG_H
#define FIRMWARE_BOARDS_STM32G431KB_G4_WATCHDOG_H

#include <stdbool.h>
#include <stdint.h>

#define G4_WATCHDOG_LSI_HZ 32000u /* nominal; the LSI varies by a few per cent */
#define G4_WATCHDOG_TIMEOUT_MAX_MS 32768u /* divider 256, reload 4096 */

/* Starts the watchdog with a timeout of `timeout_ms` (at the nominal LSI, up to 32 s);
 * false if its registers did not take the values. */
bool g4_watchdog_start(uint32_t timeout_ms);

void g4_watchdog_refresh(void);

#endif /* FIRMWARE_BOARDS_STM32G431KB_G4_WATCHDOG_H */
