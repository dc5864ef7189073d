/* The sample clock: the time of every IMU sample on the node's microsecond timer.
 *
 * The IMU samples on its own oscillator (the ICM-42688-P's ODR is off nominal by up to
 * +-2 %), stores the samples in its FIFO, and raises INT1 when the FIFO count crosses
 * the watermark W from below. The node reads the FIFO late and irregularly. The clock
 * numbers the samples (index 0 = the first one written after the FIFO was flushed) and
 * fits a line  time = a + period * index  to the interrupt edges:
 *
 * 1. Which sample raised an edge: when the count crossed W, the FIFO held the samples
 *    [popped, popped + W - 1], `popped` being the samples the node had read out by then;
 *    so the edge belongs to sample popped + W - 1. The clock keeps a log of the last
 *    SAMPLE_CLOCK_READ_LOG FIFO reads (node timer at their start and end, indices before
 *    and after) to know `popped` at the edge's time even when the interrupt is handed
 *    over after later reads. An edge inside a read (the count can cross W while the
 *    read drains the FIFO) is ambiguous: once the line exists it takes the index the
 *    line predicts when that is unambiguous (within a quarter sample), else it is
 *    dropped.
 * 2. The line: least squares over the last SAMPLE_CLOCK_FIT_SIZE edges, exact in int64
 *    relative to the oldest edge (period in 1/65536 us: the fit is integer arithmetic and
 *    agrees bit for bit on the host and the MCU; no double), refitted at each edge (64
 *    int64 products per sum, at tens to hundreds of edges a second). With one edge
 *    the period is the nominal one. An edge further from the line than the interrupt
 *    jitter allows (plus the line's own uncertainty) is rejected; three rejections in a
 *    row start the line again from the last edge.
 * 3. A sample's time = the line at its index - the interrupt latency + 0.5 us (the
 *    timer read in the interrupt is the floor of the true time), rounded to the
 *    microsecond. Samples read after the last edge (up to the read's lateness) are
 *    extrapolated along the fitted period.
 * The times mark when the chip wrote each sample to its FIFO (its INT1 edge), not the
 * chip's filter delay before that (a constant of its filter settings).
 *
 * Restart (sample_clock_restart) after every FIFO flush: configuration, ODR change,
 * overflow (samples lost: the node reports it). Interrupts that rose before the restart
 * are discarded. The 32-bit microsecond timer may wrap anywhere: all time arithmetic is
 * modulo 2^32 (intervals up to 35 minutes).
 *
 * Accuracy (tests/test_sample_clock.c; the program firmware_test_sample_clock prints
 * the max and 99th percentile of each run): driver + fake chip + clock, 60 s at 1 kHz,
 * watermark 10, the FIFO read 0..30 ms after each edge over a 1 MHz I2C bus, interrupt
 * latency 0..10 us, the chip's ODR off by -2 %, +1.3 % or +2 % or drifting 3 ppm/s:
 * every settled sample within 3 us of the instant the chip took it (p99 about 2 us).
 * Settling: `settle_interrupts` (40) edges after each restart, about 1 s there; until then
 * the stamps come with SAMPLE_CLOCK_SETTLING (the first edges' stamps can be hundreds of
 * us off). A faster drift of the chip's oscillator (tens of ppm per second) bends the
 * sample times more than a line over 64 edges follows: the error then grows past 5 us.
 *
 * Use from the node (interrupt time = node timer read in the INT1 handler):
 *   configure / flush:  sample_clock_restart(&clock, period_us, watermark, dev.fifo_flush_us)
 *   each INT1 edge:     sample_clock_interrupt(&clock, irq_time_us)   (in order)
 *   each FIFO read:     start = now; icm42688_read_fifo(..., &n, ...); end = now;
 *                       sample_clock_stamp(&clock, start, end, n, times_us)
 */
#ifndef FIRMWARE_CORE_SAMPLE_CLOCK_H
#define FIRMWARE_CORE_SAMPLE_CLOCK_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define SAMPLE_CLOCK_FIT_SIZE 64u /* interrupt edges in the line fit */
#define SAMPLE_CLOCK_READ_LOG 4u  /* FIFO reads remembered to place late interrupts */

typedef struct {
  float interrupt_latency_us; /* mean delay from the INT1 edge to the timer reading in
                                 the handler, us (the board's; 0 with a timer capture) */
  float interrupt_jitter_us;  /* spread of that delay (max - min), us */
  float max_rate_error;       /* bound on the chip's ODR error, fraction (0.03 = 3 %) */
  uint16_t settle_interrupts; /* edges in the fit before the times count as settled */
} sample_clock_settings_t;

/* Latency 0, jitter 10 us, ODR within 3 %, settled after 40 edges. */
extern const sample_clock_settings_t sample_clock_settings_default;

typedef enum {
  SAMPLE_CLOCK_OK = 0,   /* times from a settled fit */
  SAMPLE_CLOCK_SETTLING, /* fewer edges than settle_interrupts: times less accurate */
  SAMPLE_CLOCK_NO_LOCK,  /* no edge since the restart: times guessed from the read */
} sample_clock_status_t;

typedef struct {
  uint32_t index;   /* sample index since the restart */
  uint32_t time_us; /* node timer at the edge (as read in the handler) */
} sample_clock_edge_t;

typedef struct {
  uint32_t start_us;    /* node timer before the read */
  uint32_t end_us;      /* after it */
  uint32_t index_after; /* samples read out since the restart, after it */
  uint32_t index_before;
} sample_clock_read_t;

typedef struct {
  sample_clock_settings_t settings;
  int64_t nominal_period_q16; /* us / 65536 */
  uint32_t watermark_samples;
  uint32_t restart_us; /* node timer at the restart (FIFO flush) */
  uint32_t next_index; /* index of the next sample to stamp */
  sample_clock_read_t reads[SAMPLE_CLOCK_READ_LOG];
  uint32_t read_total; /* reads since the restart */
  sample_clock_edge_t edges[SAMPLE_CLOCK_FIT_SIZE];
  uint32_t edge_head; /* oldest edge */
  uint32_t edge_count;
  /* the line: time(index) = origin_time_us + (base_q16 + period_q16 * (index - origin_index)) /
   * 2^16 */
  uint32_t origin_index;
  uint32_t origin_time_us;
  int64_t base_q16;
  int64_t period_q16;
  int64_t mean_index_q16; /* of the fitted edges, relative to origin_index */
  uint32_t span_samples;  /* newest - oldest fitted edge */
  uint32_t rejected_in_row;
  /* statistics since init */
  uint32_t edges_used;
  uint32_t edges_in_read;   /* of which inside a read, placed by the line */
  uint32_t edges_ambiguous; /* inside a read and not resolvable: dropped */
  uint32_t edges_rejected;  /* too far from the line */
  uint32_t edges_stale;     /* before the restart */
  uint32_t restarts;
} sample_clock_t;

void sample_clock_init(sample_clock_t *const clock, const sample_clock_settings_t *const settings);

/* Starts again after a FIFO flush at `restart_us` (node timer): samples of `period_us`
 * (nominal), edges every `watermark_samples` packets. */
void sample_clock_restart(sample_clock_t *const clock, uint32_t period_us,
                          uint32_t watermark_samples, uint32_t restart_us);

/* An INT1 edge, its handler having read the node timer at `irq_time_us`. Call for every
 * edge, in order, before or after the FIFO reads that followed it. */
void sample_clock_interrupt(sample_clock_t *const clock, uint32_t irq_time_us);

/* The times of `count` samples just read from the FIFO (oldest first) by a read that
 * began at `read_start_us` and ended at `read_end_us`, into `times_us`. */
sample_clock_status_t sample_clock_stamp(sample_clock_t *const clock, uint32_t read_start_us,
                                         uint32_t read_end_us, size_t count,
                                         uint32_t *const times_us);

/* The measured sample period, us (the nominal one before two edges): the interval the
 * filter integrates over. */
float sample_clock_period_us(const sample_clock_t *const clock);

#endif /* FIRMWARE_CORE_SAMPLE_CLOCK_H */
