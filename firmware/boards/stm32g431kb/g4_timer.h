/* TIM2, the node's microsecond clock: a 32-bit counter at 1 MHz (170 MHz / 170) that wraps
 * every 2^32 us (71.6 min), as bus_t.now_us promises.
 *
 * Channel 1 captures the IMU's INT1 line (PA0, AF1) on its rising edge in hardware: the
 * captured count is the edge's time to the microsecond, whatever the interrupt latency.
 * The input filter (8 samples of the 170 MHz clock, 47 ns) adds a constant delay only.
 * Channel 2 compares: a 1 ms tick that wakes the main loop (heartbeats, magnetometer
 * reads, retries) when no other interrupt does.
 */
#ifndef FIRMWARE_BOARDS_STM32G431KB_G4_TIMER_H
#define FIRMWARE_BOARDS_STM32G431KB_G4_TIMER_H

#include <stdbool.h>
#include <stdint.h>

#define G4_TIMER_HZ 1000000u      /* counter rate: 1 us per count */
#define G4_TIMER_TICK_US 1000u    /* main-loop wake-up period */

typedef struct {
  bool captured;          /* an INT1 edge was captured */
  uint32_t capture_us;    /* its time */
  bool capture_missed;    /* another edge came before the previous one was read */
  bool tick;              /* the 1 ms tick elapsed */
} g4_timer_events_t;

/* Starts TIM2 from kernel clock `timer_clock_hz` (a multiple of 1 MHz). */
void g4_timer_init(uint32_t timer_clock_hz);

uint32_t g4_timer_now_us(void);

/* Busy-waits at least `microseconds`. */
void g4_timer_delay_us(uint32_t microseconds);

/* From the TIM2 interrupt: what happened, flags cleared, next tick scheduled. */
g4_timer_events_t g4_timer_service(void);

#endif /* FIRMWARE_BOARDS_STM32G431KB_G4_TIMER_H */
