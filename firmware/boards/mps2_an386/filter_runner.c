/* The orientation filter on recorded samples, in QEMU's mps2-an386 (Cortex-M4F).
 *
 * Reads `imu_in.bin` from QEMU's working directory through semihosting, runs the filter
 * on every sample and writes `imu_out.bin` (README.md has both formats), then prints
 * the filter's cost on QEMU's standard output:
 *   filter samples=N chunk_samples=K filter_ticks=A empty_ticks=B calibration_ticks=C
 *          calibration_instructions=D
 * SysTick (core clock) is read around the filter's loop over each chunk of K samples
 * (A), and around the same loop calling empty functions of the same signatures (B).
 * Under `-icount shift=0` virtual time advances 1 ns per instruction, so ticks count
 * instructions: the calibration loop executes D instructions in C ticks, and the
 * filter costs (A - B) * D / C / N instructions per sample.
 */
#include <stdbool.h>
#include <stdint.h>

#include "board_text.h"
#include "cortex_m.h"
#include "imu_filter.h"
#include "semihosting.h"

#define INPUT_MAGIC 0x31554D49u /* "IMU1" */
#define INPUT_FLAG_9D 1u
#define CHUNK_SAMPLES 256u
#define CALIBRATION_LOOPS 1000000u /* 2 instructions each */

typedef struct {
  uint32_t magic;
  uint32_t samples;
  float sample_period_s;
  uint32_t flags;
} input_header_t;

typedef struct {
  float gyr_rads[3];
  float acc_mps2[3];
  float mag_ut[3];
} input_sample_t;

typedef void (*update_fn)(imu_filter_t *const, const float *, const float *, const float *);
typedef void (*quaternion_fn)(const imu_filter_t *const, float *);

static input_sample_t chunk_in[CHUNK_SAMPLES];
static float chunk_out[CHUNK_SAMPLES][4];
static imu_filter_t filter;

__attribute__((noinline)) static void empty_update(imu_filter_t *const f, const float *gyr,
                                                   const float *acc, const float *mag) {
  __asm__ volatile("" : : "r"(f), "r"(gyr), "r"(acc), "r"(mag) : "memory");
}

__attribute__((noinline)) static void empty_quaternion(const imu_filter_t *const f,
                                                       float *q_wxyz) {
  __asm__ volatile("" : : "r"(f), "r"(q_wxyz) : "memory");
}

static void systick_start(void) {
  SYST_RVR = SYST_MAX_RELOAD;
  SYST_CVR = 0u;
  SYST_CSR = SYST_CSR_ENABLE | SYST_CSR_CLKSOURCE_CORE; /* no interrupt */
}

/* Runs `update` and `quaternion` over a chunk; returns the SysTick ticks it took. */
__attribute__((noinline)) static uint32_t timed_chunk(update_fn update, quaternion_fn quaternion,
                                                      uint32_t count, bool use_mag) {
  const uint32_t start = SYST_CVR;
  for (uint32_t i = 0u; i < count; i++) {
    update(&filter, chunk_in[i].gyr_rads, chunk_in[i].acc_mps2,
           use_mag ? chunk_in[i].mag_ut : 0);
    quaternion(&filter, chunk_out[i]);
  }
  return (start - SYST_CVR) & SYST_MAX_RELOAD;
}

/* A loop of exactly 2 instructions per turn (subs, bne). */
__attribute__((noinline)) static uint32_t calibration_ticks(void) {
  uint32_t loops = CALIBRATION_LOOPS;
  const uint32_t start = SYST_CVR;
  __asm__ volatile("1: subs %0, %0, #1\n\tbne 1b" : "+r"(loops) : : "cc");
  return (start - SYST_CVR) & SYST_MAX_RELOAD;
}

static void print_field(const char *name, uint32_t value) {
  char number[BOARD_TEXT_U32_MAX];
  board_text_u32(value, number);
  semihosting_write_text(name);
  semihosting_write_text(number);
}

int main(void) {
  systick_start();
  const int in = semihosting_open("imu_in.bin", SEMIHOSTING_READ);
  const int out = semihosting_open("imu_out.bin", SEMIHOSTING_WRITE);
  input_header_t header;
  if (in < 0 || out < 0 || semihosting_read(in, &header, sizeof header) != (long)sizeof header ||
      header.magic != INPUT_MAGIC || !(header.sample_period_s > 0.0f)) {
    semihosting_write_text("filter: cannot read imu_in.bin\n");
    return 2;
  }
  const bool use_mag = (header.flags & INPUT_FLAG_9D) != 0u;
  imu_filter_init(&filter, &imu_filter_settings_default, header.sample_period_s);
  uint32_t filter_ticks = 0u;
  uint32_t empty_ticks = 0u;
  for (uint32_t done = 0u; done < header.samples;) {
    const uint32_t left = header.samples - done;
    const uint32_t count = left < CHUNK_SAMPLES ? left : CHUNK_SAMPLES;
    const long bytes = (long)(count * sizeof(input_sample_t));
    if (semihosting_read(in, chunk_in, (size_t)bytes) != bytes) {
      semihosting_write_text("filter: imu_in.bin is short\n");
      return 3;
    }
    empty_ticks += timed_chunk(empty_update, empty_quaternion, count, use_mag);
    filter_ticks += timed_chunk(imu_filter_update, imu_filter_quaternion, count, use_mag);
    if (semihosting_write(out, chunk_out, count * sizeof chunk_out[0]) != 0) {
      return 4;
    }
    done += count;
  }
  semihosting_close(in);
  semihosting_close(out);
  print_field("filter samples=", header.samples);
  print_field(" chunk_samples=", CHUNK_SAMPLES);
  print_field(" filter_ticks=", filter_ticks);
  print_field(" empty_ticks=", empty_ticks);
  print_field(" calibration_ticks=", calibration_ticks());
  print_field(" calibration_instructions=", 2u * CALIBRATION_LOOPS);
  semihosting_write_text("\n");
  return 0;
}
