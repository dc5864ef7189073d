/* Nominal bit timing of the G4's FDCAN (classic CAN, or the arbitration phase of CAN FD),
 * computed from its kernel clock: no hardware, so the host tests check it.
 *
 * A bit is 1 (sync) + tseg1 + tseg2 time quanta of `prescaler` kernel clocks; the bus
 * samples at the end of tseg1. The smallest prescaler whose quanta divide the bit exactly
 * is chosen (the finest resolution, which CiA 601-3 recommends), the sample point as
 * near the request as the quanta allow, and the resynchronisation jump width as large as
 * tseg2 (the widest oscillator tolerance). Register limits from RM0440 (FDCAN_NBTP).
 */
#ifndef FIRMWARE_BOARDS_STM32G431KB_G4_FDCAN_TIMING_H
#define FIRMWARE_BOARDS_STM32G431KB_G4_FDCAN_TIMING_H

#include <stdbool.h>
#include <stdint.h>

#define G4_FDCAN_PRESCALER_MAX 512u /* NBRP + 1 */
#define G4_FDCAN_TSEG1_MIN 2u       /* NTSEG1 + 1, tq */
#define G4_FDCAN_TSEG1_MAX 256u
#define G4_FDCAN_TSEG2_MIN 2u       /* tq: at least the information processing time */
#define G4_FDCAN_TSEG2_MAX 128u     /* NTSEG2 + 1 */
#define G4_FDCAN_SJW_MAX 128u       /* NSJW + 1 */
#define G4_FDCAN_TQ_PER_BIT_MIN 8u  /* below this the sample point is too coarse */
#define G4_FDCAN_NOMINAL_BPS_MAX 1000000u /* classic CAN, and CAN FD's arbitration phase */

typedef struct {
  uint16_t prescaler;          /* kernel clocks per time quantum, 1..512 */
  uint16_t tseg1_tq;           /* propagation + phase 1, tq */
  uint16_t tseg2_tq;           /* phase 2, tq */
  uint16_t sjw_tq;             /* resynchronisation jump width, tq */
  uint16_t tq_per_bit;         /* 1 + tseg1 + tseg2 */
  uint16_t sample_point_permille; /* (1 + tseg1) / tq_per_bit, per mille */
} g4_fdcan_timing_t;

/* False when no prescaler divides `kernel_hz` into `bitrate_bps` exactly within limits. */
bool g4_fdcan_timing_compute(uint32_t kernel_hz, uint32_t bitrate_bps,
                             uint16_t sample_point_permille, g4_fdcan_timing_t *const timing);

/* The FDCAN_NBTP register value (every field stored minus one). */
uint32_t g4_fdcan_timing_nbtp(const g4_fdcan_timing_t *const timing);

/* The oscillator tolerance the timing allows (ISO 11898-1 conditions, tseg1 taken as the
 * phase segment 1, no propagation delay), parts per million. */
uint32_t g4_fdcan_timing_tolerance_ppm(const g4_fdcan_timing_t *const timing);

#endif /* FIRMWARE_BOARDS_STM32G431KB_G4_FDCAN_TIMING_H */
