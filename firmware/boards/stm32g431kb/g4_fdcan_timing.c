/* FDCAN nominal bit timing from the kernel clock (g4_fdcan_timing.h). */
#include "g4_fdcan_timing.h"

#define TQ_PER_BIT_MAX (1u + G4_FDCAN_TSEG1_MAX + G4_FDCAN_TSEG2_MAX)

static uint32_t min_u32(uint32_t a, uint32_t b) { return a < b ? a : b; }

/* Segments for `tq_per_bit` quanta and the requested sample point; false if out of range. */
static bool g4_fdcan_timing_segments(uint32_t tq_per_bit, uint16_t sample_point_permille,
                                     g4_fdcan_timing_t *const timing) {
  const uint32_t after_sample = (1000u - sample_point_permille) * tq_per_bit;
  const uint32_t tseg2 = (after_sample + 500u) / 1000u; /* nearest quantum */
  if (tseg2 < G4_FDCAN_TSEG2_MIN || tseg2 > G4_FDCAN_TSEG2_MAX || tseg2 + 1u >= tq_per_bit) {
    return false;
  }
  const uint32_t tseg1 = tq_per_bit - 1u - tseg2;
  if (tseg1 < G4_FDCAN_TSEG1_MIN || tseg1 > G4_FDCAN_TSEG1_MAX) {
    return false;
  }
  timing->tseg1_tq = (uint16_t)tseg1;
  timing->tseg2_tq = (uint16_t)tseg2;
  timing->sjw_tq = (uint16_t)min_u32(tseg2, G4_FDCAN_SJW_MAX);
  timing->tq_per_bit = (uint16_t)tq_per_bit;
  timing->sample_point_permille = (uint16_t)((1000u * (1u + tseg1) + tq_per_bit / 2u) / tq_per_bit);
  return true;
}

bool g4_fdcan_timing_compute(uint32_t kernel_hz, uint32_t bitrate_bps,
                             uint16_t sample_point_permille, g4_fdcan_timing_t *const timing) {
  if (bitrate_bps == 0u || bitrate_bps > G4_FDCAN_NOMINAL_BPS_MAX || sample_point_permille == 0u ||
      sample_point_permille >= 1000u) {
    return false;
  }
  for (uint32_t prescaler = 1u; prescaler <= G4_FDCAN_PRESCALER_MAX; prescaler++) {
    const uint32_t quantum_hz = bitrate_bps * prescaler; /* < 2^32: 1 Mbit/s x 512 */
    if (kernel_hz % quantum_hz != 0u) {
      continue; /* the bit would not be a whole number of quanta */
    }
    const uint32_t tq_per_bit = kernel_hz / quantum_hz;
    if (tq_per_bit > TQ_PER_BIT_MAX) {
      continue;
    }
    if (tq_per_bit < G4_FDCAN_TQ_PER_BIT_MIN) {
      return false; /* larger prescalers only make fewer quanta */
    }
    if (g4_fdcan_timing_segments(tq_per_bit, sample_point_permille, timing)) {
      timing->prescaler = (uint16_t)prescaler;
      return true;
    }
  }
  return false;
}

uint32_t g4_fdcan_timing_nbtp(const g4_fdcan_timing_t *const timing) {
  return ((uint32_t)(timing->sjw_tq - 1u) << 25) | ((uint32_t)(timing->prescaler - 1u) << 16) |
         ((uint32_t)(timing->tseg1_tq - 1u) << 8) | (uint32_t)(timing->tseg2_tq - 1u);
}

uint32_t g4_fdcan_timing_tolerance_ppm(const g4_fdcan_timing_t *const timing) {
  /* df <= SJW / (20 * bit) and df <= min(phase1, phase2) / (2 * (13 * bit - phase2)). */
  const uint32_t bit = timing->tq_per_bit;
  const uint32_t phase = min_u32(timing->tseg1_tq, timing->tseg2_tq);
  const uint32_t by_sjw = (uint32_t)(1000000ull * timing->sjw_tq / (20ull * bit));
  const uint32_t by_phase = (uint32_t)(1000000ull * phase / (2ull * (13ull * bit - timing->tseg2_tq)));
  return min_u32(by_sjw, by_phase);
}
