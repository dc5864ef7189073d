/* The sample clock (method: sample_clock.h). Fixed point: times in us * 2^16 (Q16)
 * relative to the oldest fitted edge, in int64. */
#include "sample_clock.h"

#include <string.h>

#define SAMPLE_CLOCK_Q16 65536
#define SAMPLE_CLOCK_GATE_FLOOR_Q16 (4 * SAMPLE_CLOCK_Q16) /* us added to every gate */
#define SAMPLE_CLOCK_REJECTS_TO_RESTART 3u

const sample_clock_settings_t sample_clock_settings_default = {
    .interrupt_latency_us = 0.0f,
    .interrupt_jitter_us = 10.0f,
    .max_rate_error = 0.03f,
    .settle_interrupts = 40u,
};

typedef enum {
  SAMPLE_CLOCK_PLACED,   /* the samples read out at the edge are known */
  SAMPLE_CLOCK_IN_READ,  /* the edge fell inside a read: known to a range */
  SAMPLE_CLOCK_UNPLACED, /* before every remembered read */
} sample_clock_place_t;

/* a - b on the wrapping timer (or index), as a signed interval. */
static int32_t sample_clock_diff(uint32_t a, uint32_t b) { return (int32_t)(a - b); }

static int64_t sample_clock_round_div(int64_t numerator, int64_t denominator) {
  return numerator >= 0 ? (numerator + denominator / 2) / denominator
                        : -((-numerator + denominator / 2) / denominator);
}

static int64_t sample_clock_abs(int64_t value) { return value < 0 ? -value : value; }

static int64_t sample_clock_q16(float microseconds) {
  return (int64_t)(microseconds * (float)SAMPLE_CLOCK_Q16);
}

void sample_clock_init(sample_clock_t *const clock, const sample_clock_settings_t *const settings) {
  memset(clock, 0, sizeof(*clock));
  clock->settings = *settings;
  clock->nominal_period_q16 = SAMPLE_CLOCK_Q16;
  clock->watermark_samples = 1u;
}

static void sample_clock_forget_edges(sample_clock_t *const clock) {
  clock->edge_head = 0u;
  clock->edge_count = 0u;
  clock->rejected_in_row = 0u;
  clock->period_q16 = clock->nominal_period_q16;
  clock->base_q16 = 0;
  clock->mean_index_q16 = 0;
  clock->span_samples = 0u;
}

void sample_clock_restart(sample_clock_t *const clock, uint32_t period_us,
                          uint32_t watermark_samples, uint32_t restart_us) {
  clock->nominal_period_q16 = (int64_t)period_us * SAMPLE_CLOCK_Q16;
  clock->watermark_samples = watermark_samples > 0u ? watermark_samples : 1u;
  clock->restart_us = restart_us;
  clock->next_index = 0u;
  clock->read_total = 0u;
  clock->restarts++;
  sample_clock_forget_edges(clock);
}

/* The line at `index`, Q16 us relative to origin_time_us. */
static int64_t sample_clock_line_q16(const sample_clock_t *const clock, uint32_t index) {
  return clock->base_q16 +
         clock->period_q16 * (int64_t)sample_clock_diff(index, clock->origin_index);
}

/* Least squares over the stored edges (exact sums relative to the oldest edge). */
static void sample_clock_fit(sample_clock_t *const clock) {
  const sample_clock_edge_t *const oldest = &clock->edges[clock->edge_head];
  const int64_t n = clock->edge_count;
  int64_t sk = 0, st = 0, skk = 0, skt = 0;
  uint32_t newest_dk = 0u;
  for (uint32_t i = 0; i < clock->edge_count; ++i) {
    const sample_clock_edge_t *const edge =
        &clock->edges[(clock->edge_head + i) % SAMPLE_CLOCK_FIT_SIZE];
    const int64_t dk = sample_clock_diff(edge->index, oldest->index);
    const int64_t dt = sample_clock_diff(edge->time_us, oldest->time_us);
    sk += dk;
    st += dt;
    skk += dk * dk;
    skt += dk * dt;
    newest_dk = (uint32_t)dk;
  }
  clock->origin_index = oldest->index;
  clock->origin_time_us = oldest->time_us;
  clock->span_samples = newest_dk;
  clock->mean_index_q16 = sample_clock_round_div(sk * SAMPLE_CLOCK_Q16, n);
  const int64_t denominator = n * skk - sk * sk;
  if (n < 2 || denominator <= 0) {
    clock->period_q16 = clock->nominal_period_q16;
    clock->base_q16 = 0;
    return;
  }
  const int64_t numerator = n * skt - sk * st;
  const int64_t whole = numerator / denominator;
  const int64_t rest = numerator % denominator;
  clock->period_q16 =
      whole * SAMPLE_CLOCK_Q16 + sample_clock_round_div(rest * SAMPLE_CLOCK_Q16, denominator);
  /* through the centroid: t0 + st/n = line(k0 + sk/n) */
  clock->base_q16 = sample_clock_round_div(st * SAMPLE_CLOCK_Q16 - clock->period_q16 * sk, n);
}

static bool sample_clock_period_plausible(const sample_clock_t *const clock) {
  const int64_t error = sample_clock_abs(clock->period_q16 - clock->nominal_period_q16);
  const int64_t bound =
      (int64_t)((float)clock->nominal_period_q16 * (2.0f * clock->settings.max_rate_error));
  return error <= bound;
}

static void sample_clock_add_edge(sample_clock_t *const clock, uint32_t index, uint32_t time_us) {
  if (clock->edge_count == SAMPLE_CLOCK_FIT_SIZE) {
    clock->edge_head = (clock->edge_head + 1u) % SAMPLE_CLOCK_FIT_SIZE;
    clock->edge_count--;
  }
  sample_clock_edge_t *const edge =
      &clock->edges[(clock->edge_head + clock->edge_count) % SAMPLE_CLOCK_FIT_SIZE];
  edge->index = index;
  edge->time_us = time_us;
  clock->edge_count++;
  clock->edges_used++;
  sample_clock_fit(clock);
  if (!sample_clock_period_plausible(clock)) { /* a bad association: start from this edge */
    sample_clock_forget_edges(clock);
    clock->edges[0] = (sample_clock_edge_t){.index = index, .time_us = time_us};
    clock->edge_count = 1u;
    sample_clock_fit(clock);
  }
}

/* How far an edge at `index` may lie from the line, Q16 us. */
static int64_t sample_clock_gate_q16(const sample_clock_t *const clock, uint32_t index) {
  const int64_t jitter_q16 = sample_clock_q16(clock->settings.interrupt_jitter_us);
  const int64_t gate_q16 = 2 * jitter_q16 + SAMPLE_CLOCK_GATE_FLOOR_Q16;
  const int64_t dk = sample_clock_diff(index, clock->origin_index);
  if (clock->edge_count < 2u) { /* the nominal period, off by up to max_rate_error */
    const int64_t rate_ppm = (int64_t)(clock->settings.max_rate_error * 1.0e6f);
    return gate_q16 + (clock->nominal_period_q16 * rate_ppm / 1000000) * sample_clock_abs(dk);
  }
  const int64_t distance_q16 = sample_clock_abs(dk * SAMPLE_CLOCK_Q16 - clock->mean_index_q16);
  const int64_t span = clock->span_samples > 0u ? clock->span_samples : 1u;
  return gate_q16 + 2 * jitter_q16 * (distance_q16 / SAMPLE_CLOCK_Q16) / span;
}

static void sample_clock_consider(sample_clock_t *const clock, uint32_t index, uint32_t time_us) {
  if (clock->edge_count > 0u) {
    const sample_clock_edge_t *const newest =
        &clock->edges[(clock->edge_head + clock->edge_count - 1u) % SAMPLE_CLOCK_FIT_SIZE];
    const int64_t residual_q16 =
        (int64_t)sample_clock_diff(time_us, clock->origin_time_us) * SAMPLE_CLOCK_Q16 -
        sample_clock_line_q16(clock, index);
    const bool forward = sample_clock_diff(index, newest->index) > 0;
    if (!forward || sample_clock_abs(residual_q16) > sample_clock_gate_q16(clock, index)) {
      clock->edges_rejected++;
      if (++clock->rejected_in_row < SAMPLE_CLOCK_REJECTS_TO_RESTART) return;
      sample_clock_forget_edges(clock);
    }
  }
  clock->rejected_in_row = 0u;
  sample_clock_add_edge(clock, index, time_us);
}

/* Samples read out when the edge rose: from the read log. */
static sample_clock_place_t sample_clock_place(const sample_clock_t *const clock,
                                               uint32_t irq_time_us, uint32_t *const popped_low,
                                               uint32_t *const popped_high) {
  const float latency = clock->settings.interrupt_latency_us;
  const float half_jitter = 0.5f * clock->settings.interrupt_jitter_us;
  const uint32_t earliest = irq_time_us - (uint32_t)(int32_t)(latency + half_jitter + 1.0f);
  const uint32_t latest = irq_time_us - (uint32_t)(int32_t)(latency - half_jitter - 1.0f);
  const uint32_t logged =
      clock->read_total < SAMPLE_CLOCK_READ_LOG ? clock->read_total : SAMPLE_CLOCK_READ_LOG;
  for (uint32_t j = 0; j < logged; ++j) {
    const sample_clock_read_t *const read =
        &clock->reads[(clock->read_total - 1u - j) % SAMPLE_CLOCK_READ_LOG];
    *popped_low = read->index_before;
    *popped_high = read->index_after;
    if (sample_clock_diff(earliest, read->end_us) >= 0) {
      *popped_low = read->index_after;
      return SAMPLE_CLOCK_PLACED;
    }
    if (sample_clock_diff(latest, read->start_us) >= 0) return SAMPLE_CLOCK_IN_READ;
  }
  *popped_low = 0u; /* before every read since the restart, if all are remembered */
  *popped_high = 0u;
  return clock->read_total <= SAMPLE_CLOCK_READ_LOG ? SAMPLE_CLOCK_PLACED : SAMPLE_CLOCK_UNPLACED;
}

/* The index the line predicts for an edge at `time_us`; false when not within a
 * quarter sample of one. */
static bool sample_clock_predict(const sample_clock_t *const clock, uint32_t time_us,
                                 uint32_t *const index) {
  if (clock->edge_count < 2u) return false;
  const int64_t offset_q16 =
      (int64_t)sample_clock_diff(time_us, clock->origin_time_us) * SAMPLE_CLOCK_Q16 -
      clock->base_q16;
  const int64_t nearest = sample_clock_round_div(offset_q16, clock->period_q16);
  const int64_t miss_q16 = sample_clock_abs(offset_q16 - nearest * clock->period_q16);
  *index = clock->origin_index + (uint32_t)(int32_t)nearest;
  return miss_q16 * 4 <= clock->period_q16;
}

void sample_clock_interrupt(sample_clock_t *const clock, uint32_t irq_time_us) {
  const float guard = clock->settings.interrupt_latency_us + clock->settings.interrupt_jitter_us;
  if ((float)sample_clock_diff(irq_time_us, clock->restart_us) < guard) {
    clock->edges_stale++;
    return;
  }
  uint32_t low = 0u, high = 0u, index = 0u;
  const uint32_t last = clock->watermark_samples - 1u;
  const sample_clock_place_t place = sample_clock_place(clock, irq_time_us, &low, &high);
  if (place == SAMPLE_CLOCK_PLACED) {
    sample_clock_consider(clock, low + last, irq_time_us);
    return;
  }
  const bool predicted = sample_clock_predict(clock, irq_time_us, &index);
  const bool in_range =
      place == SAMPLE_CLOCK_UNPLACED ||
      (sample_clock_diff(index, low + last) >= 0 && sample_clock_diff(index, high + last) <= 0);
  if (predicted && in_range) {
    clock->edges_in_read++;
    sample_clock_consider(clock, index, irq_time_us);
  } else {
    clock->edges_ambiguous++;
  }
}

/* The stamp of sample `index`, node timer us. */
static uint32_t sample_clock_time_of(const sample_clock_t *const clock, uint32_t index) {
  const int64_t correction_q16 =
      SAMPLE_CLOCK_Q16 / 2 - sample_clock_q16(clock->settings.interrupt_latency_us);
  const int64_t offset_q16 = sample_clock_line_q16(clock, index) + correction_q16;
  return clock->origin_time_us +
         (uint32_t)(int32_t)sample_clock_round_div(offset_q16, SAMPLE_CLOCK_Q16);
}

static void sample_clock_log_read(sample_clock_t *const clock, uint32_t start_us, uint32_t end_us,
                                  uint32_t count) {
  sample_clock_read_t *const read = &clock->reads[clock->read_total % SAMPLE_CLOCK_READ_LOG];
  read->start_us = start_us;
  read->end_us = end_us;
  read->index_before = clock->next_index;
  read->index_after = clock->next_index + count;
  clock->read_total++;
  clock->next_index += count;
}

sample_clock_status_t sample_clock_stamp(sample_clock_t *const clock, uint32_t read_start_us,
                                         uint32_t read_end_us, size_t count,
                                         uint32_t *const times_us) {
  const uint32_t nominal_us = (uint32_t)(clock->nominal_period_q16 / SAMPLE_CLOCK_Q16);
  for (size_t i = 0; i < count; ++i) {
    times_us[i] = clock->edge_count > 0u
                      ? sample_clock_time_of(clock, clock->next_index + (uint32_t)i)
                      : read_start_us - nominal_us * (uint32_t)(count - 1u - i);
  }
  const sample_clock_status_t status = clock->edge_count == 0u ? SAMPLE_CLOCK_NO_LOCK
                                       : clock->edge_count < clock->settings.settle_interrupts
                                           ? SAMPLE_CLOCK_SETTLING
                                           : SAMPLE_CLOCK_OK;
  if (count > 0u) sample_clock_log_read(clock, read_start_us, read_end_us, (uint32_t)count);
  return status;
}

float sample_clock_period_us(const sample_clock_t *const clock) {
  return (float)clock->period_q16 / (float)SAMPLE_CLOCK_Q16;
}
