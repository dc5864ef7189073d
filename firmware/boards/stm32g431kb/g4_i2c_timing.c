/* I2C TIMINGR from the kernel clock (g4_i2c_timing.h). Times in picoseconds, 64-bit. */
#include "g4_i2c_timing.h"

#define PS_PER_S 1000000000000ll
#define PS_PER_NS 1000ll
#define FIELD_MAX_4BIT 15
#define FIELD_MAX_8BIT 255

/* The mode's limits (UM10204 table 10), ns. */
typedef struct {
  uint32_t max_hz;
  int64_t low_min_ns, high_min_ns;
  int64_t setup_min_ns;      /* tSU;DAT (tHD;DAT min is 0 in every mode) */
  int64_t valid_max_ns;      /* tVD;DAT: SCL low to data valid */
  uint32_t rise_max_ns, fall_max_ns;
} i2c_mode_t;

static const i2c_mode_t i2c_modes[] = {
    {100000u, 4700, 4000, 250, 3450, 1000u, 300u},
    {400000u, 1300, 600, 100, 900, 300u, 300u},
    {1000000u, 500, 260, 50, 450, 120u, 120u},
};

/* What the computation works with, in ps. */
typedef struct {
  const i2c_mode_t *mode;
  int64_t clock, rise, fall;
  int64_t filter_min, filter_max; /* input delay of the filter */
  int64_t period;                 /* of the requested rate */
  uint8_t dnf;
} i2c_inputs_t;

static int64_t ceil_div(int64_t value, int64_t divisor) {
  return value <= 0 ? 0 : (value + divisor - 1) / divisor;
}

static int64_t max_i64(int64_t a, int64_t b) { return a > b ? a : b; }

/* Hold and set-up ticks (SDADEL, SCLDEL + 1); false if they overflow or miss tVD;DAT. */
static bool g4_i2c_timing_data(const i2c_inputs_t *const in, int64_t tick, g4_i2c_timing_t *const t) {
  const int64_t dnf = in->dnf;
  const int64_t hold = ceil_div(in->fall - in->filter_min - (dnf + 3) * in->clock, tick);
  const int64_t hold_max = in->mode->valid_max_ns * PS_PER_NS - in->rise - in->filter_max -
                           (dnf + 4) * in->clock;
  const int64_t setup = max_i64(1, ceil_div(in->rise + in->mode->setup_min_ns * PS_PER_NS, tick));
  if (hold > FIELD_MAX_4BIT || hold * tick > hold_max || setup - 1 > FIELD_MAX_4BIT) {
    return false;
  }
  t->sdadel = (uint8_t)hold;
  t->scldel = (uint8_t)(setup - 1);
  return true;
}

/* SCL low and high ticks for the limits, stretched to the requested period. */
static bool g4_i2c_timing_clock(const i2c_inputs_t *const in, int64_t tick, g4_i2c_timing_t *const t) {
  const int64_t sync_fixed = in->filter_min + (in->dnf + 2) * in->clock;
  const int64_t sync1 = in->fall + sync_fixed, sync2 = in->rise + sync_fixed;
  int64_t low = max_i64(1, ceil_div(in->mode->low_min_ns * PS_PER_NS - sync1, tick));
  int64_t high = max_i64(1, ceil_div(in->mode->high_min_ns * PS_PER_NS - sync2, tick));
  const int64_t extra = ceil_div(in->period - (sync1 + sync2 + (low + high) * tick), tick);
  low += extra - extra / 2;
  high += extra / 2;
  const int64_t low_min = sync1 + low * tick;
  /* Hold and set-up fit in the low period; RM0440: tI2CCLK < (tLOW - tfilters) / 4. */
  if (low - 1 > FIELD_MAX_8BIT || high - 1 > FIELD_MAX_8BIT || t->sdadel + t->scldel + 1 >= low ||
      4 * in->clock >= low_min - in->filter_max - in->dnf * in->clock) {
    return false;
  }
  const int64_t sync_spread = 2 * (in->filter_max - in->filter_min + in->clock);
  t->scll = (uint8_t)(low - 1);
  t->sclh = (uint8_t)(high - 1);
  t->fastest_hz = (uint32_t)(PS_PER_S / (sync1 + sync2 + (low + high) * tick));
  t->slowest_hz = (uint32_t)(PS_PER_S / (sync1 + sync2 + sync_spread + (low + high) * tick));
  t->low_min_ns = (uint32_t)(low_min / PS_PER_NS);
  t->high_min_ns = (uint32_t)((sync2 + high * tick) / PS_PER_NS);
  return true;
}

static bool g4_i2c_timing_inputs(uint32_t kernel_hz, uint32_t bus_hz, uint32_t rise_ns,
                                 uint32_t fall_ns, g4_i2c_filter_t filter, i2c_inputs_t *const in) {
  in->mode = 0;
  for (uint32_t i = 0u; i < sizeof i2c_modes / sizeof i2c_modes[0] && in->mode == 0; i++) {
    in->mode = bus_hz <= i2c_modes[i].max_hz ? &i2c_modes[i] : 0;
  }
  if (kernel_hz == 0u || bus_hz == 0u || in->mode == 0 || rise_ns > in->mode->rise_max_ns ||
      fall_ns > in->mode->fall_max_ns) {
    return false;
  }
  in->clock = PS_PER_S / kernel_hz;
  in->rise = (int64_t)rise_ns * PS_PER_NS;
  in->fall = (int64_t)fall_ns * PS_PER_NS;
  in->period = PS_PER_S / bus_hz;
  const bool analog = filter == G4_I2C_FILTER_ANALOG;
  const int64_t dnf = analog ? 0 : ceil_div(G4_I2C_SPIKE_NS * PS_PER_NS, in->clock);
  in->dnf = (uint8_t)dnf;
  in->filter_min = analog ? G4_I2C_ANALOG_FILTER_MIN_NS * PS_PER_NS : 0;
  in->filter_max = analog ? G4_I2C_ANALOG_FILTER_MAX_NS * PS_PER_NS : 0;
  return dnf <= G4_I2C_DIGITAL_FILTER_MAX;
}

bool g4_i2c_timing_compute(uint32_t kernel_hz, uint32_t bus_hz, uint32_t rise_ns,
                           uint32_t fall_ns, g4_i2c_filter_t filter,
                           g4_i2c_timing_t *const timing) {
  i2c_inputs_t in;
  if (!g4_i2c_timing_inputs(kernel_hz, bus_hz, rise_ns, fall_ns, filter, &in)) {
    return false;
  }
  for (uint8_t presc = 0u; presc <= FIELD_MAX_4BIT; presc++) {
    const int64_t tick = in.clock * (presc + 1);
    if (g4_i2c_timing_data(&in, tick, timing) && g4_i2c_timing_clock(&in, tick, timing)) {
      timing->presc = presc;
      timing->dnf = in.dnf;
      timing->timingr = ((uint32_t)presc << 28) | ((uint32_t)timing->scldel << 20) |
                        ((uint32_t)timing->sdadel << 16) | ((uint32_t)timing->sclh << 8) |
                        timing->scll;
      timing->cr1_filter = in.dnf == 0u ? 0u
                                        : G4_I2C_CR1_ANFOFF | ((uint32_t)in.dnf << G4_I2C_CR1_DNF_SHIFT);
      return true;
    }
  }
  return false;
}
