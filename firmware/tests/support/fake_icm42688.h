/* A register-level fake of TDK's ICM-42688-P behind a bus_t: the IMU for host tests of
 * the driver and the sample clock, and the IMU of the QEMU test board (QEMU models no
 * accelerometer or gyroscope). Freestanding C11: no allocation, no stdio; string.h and
 * math.h only.
 *
 * What it models (register map: drivers/icm42688_regs.h):
 *   - WHO_AM_I 0x47, register banks 0-4 (REG_BANK_SEL), soft reset (the chip NACKs for
 *     1 ms after it), register reset values;
 *   - the sensors: off until PWR_MGMT0 turns them on (writes within 200 us of that are
 *     lost and counted in timing_violations); the gyroscope reads -32768 for its first
 *     30 ms; one sample per ODR tick of GYRO_CONFIG0, at the full scales of GYRO_CONFIG0
 *     and ACCEL_CONFIG0 (round to nearest, saturating at +-32767);
 *   - its own oscillator: the ODR runs `clock_error_ppm` fast (+13000: 1.3 % fast) on
 *     the fake's clock, which the test advances (fake_icm42688_advance_*, and every
 *     delay_us of the bus); the bus's now_us is the node's timer: the fake's clock in
 *     microseconds (floor) plus `timer_offset_us`, wrapping at 2^32;
 *   - data registers and data-ready (INT_STATUS, cleared by reading it);
 *   - the FIFO: 2048 bytes = 128 packets of format 3 (16 bytes), stream mode; a full
 *     FIFO drops its oldest packet for each new one and counts it in FIFO_LOST_PKT;
 *     FIFO_COUNT in bytes or packets (FIFO_COUNT_REC), either endianness; FIFO_DATA
 *     reads pop bytes (the address does not advance); a packet read in part is read again
 *     from its start by the next transfer (FIFO_RESUME_PARTIAL_RD = 0); flush;
 *   - the watermark (FIFO_CONFIG2/3): with FIFO_WM_GT_TH = 0 one event when a write makes
 *     the count cross it from below; with 1, an event on every write at or above it;
 *   - INT1 (INT_SOURCE0: watermark, FIFO full, data-ready): pulsed (one edge per event)
 *     or latched (an edge, then high until INT_STATUS is read); no edges at all while
 *     INT_CONFIG1.INT_ASYNC_RESET keeps its reset value 1 (the datasheet requires 0);
 *   - self-test: SELF_TEST_CONFIG adds `st_*_ratio` times the factory response of the
 *     trim codes (2620 / 2^(3 - FS_SEL) * 1.01^(code - 1) LSB) to the actuated axes (the
 *     accelerometer's only with ACCEL_ST_POWER);
 *   - failures: absent (every transfer NACKs), one NACK after n transfers, stuck output
 *     (every sample repeats the last one), bus time per byte (transfers take time).
 * It records the true sampling instant of every packet read out of the FIFO
 * (fake_icm42688_take_record), oldest first, with the values the source fed.
 */
#ifndef FIRMWARE_TESTS_SUPPORT_FAKE_ICM42688_H
#define FIRMWARE_TESTS_SUPPORT_FAKE_ICM42688_H

#include <stdbool.h>
#include <stdint.h>

#include "bus.h"

#define FAKE_ICM42688_FIFO_PACKETS 128u
#define FAKE_ICM42688_PACKET_BYTES 16u
#define FAKE_ICM42688_BANKS 5u
#define FAKE_ICM42688_REGISTERS 128u
#ifndef FAKE_ICM42688_LOG_SIZE
#define FAKE_ICM42688_LOG_SIZE 256u /* packets read out and not yet taken by the test */
#endif

/* One sample as the chip took it. */
typedef struct {
  uint32_t sequence; /* samples taken since power-on, 0-based */
  int64_t time_ns;   /* true sampling instant on the fake's clock, ns */
  float gyr_rads[3]; /* what the source fed, before quantisation, rad/s */
  float acc_mps2[3]; /* m/s^2 */
} fake_icm42688_record_t;

/* The motion the chip sees at `time_ns` (the `sequence`-th sample). */
typedef void (*fake_icm42688_source_t)(void *context, uint32_t sequence, int64_t time_ns,
                                       float gyr_rads[3], float acc_mps2[3]);
/* INT1 rose at `time_ns` (the fake's clock). */
typedef void (*fake_icm42688_int1_t)(void *context, int64_t time_ns);

typedef struct {
  uint8_t address;  /* 7-bit */
  uint8_t who_am_i; /* 0x47; another chip's for tests */
  uint8_t registers[FAKE_ICM42688_BANKS][FAKE_ICM42688_REGISTERS];
  uint8_t bank;          /* REG_BANK_SEL */
  uint8_t trim_gyro[3];  /* XG/YG/ZG_ST_DATA (bank 1), OTP */
  uint8_t trim_accel[3]; /* XA/YA/ZA_ST_DATA (bank 2), OTP */
  uint8_t int_status;    /* INT_STATUS, cleared by reading */
  /* FIFO: a ring of packets with the record of each */
  uint8_t fifo[FAKE_ICM42688_FIFO_PACKETS][FAKE_ICM42688_PACKET_BYTES];
  fake_icm42688_record_t fifo_records[FAKE_ICM42688_FIFO_PACKETS];
  uint32_t fifo_head;        /* oldest packet */
  uint32_t fifo_count;       /* packets held */
  uint32_t fifo_read_offset; /* bytes of the head packet read */
  uint16_t lost_packets;     /* FIFO_LOST_PKT */
  uint16_t count_latch;      /* FIFO_COUNT as latched by COUNTH */
  bool count_latched;        /* COUNTH read in this transfer */
  bool odr_changed;          /* header ODR flags on the next packet */
  /* time */
  int64_t now_ns;                  /* the fake's clock */
  int64_t next_sample_ns;          /* INT64_MAX: sensors off */
  int64_t period_remainder;        /* of the rational ODR period */
  int64_t gyro_valid_ns;           /* gyroscope started */
  int64_t busy_until_ns;           /* soft reset in progress */
  int64_t writes_blocked_until_ns; /* after a PWR_MGMT0 change */
  int32_t clock_error_ppm;         /* oscillator: + runs fast */
  uint32_t timer_offset_us;        /* node timer at fake time 0 */
  uint32_t bus_byte_ns;            /* transfer time per byte (0: none) */
  uint32_t chip_time_us;           /* the chip's own timer (ODR units) */
  uint32_t sequence;               /* samples taken since power-on */
  /* the motion */
  fake_icm42688_source_t source; /* NULL: still, z up */
  void *source_context;
  float temp_degc;         /* die temperature, deg C */
  int16_t raw_measured[6]; /* last measured accel x y z, gyro x y z */
  int16_t raw[6];          /* data registers: actuated, invalid gyro */
  fake_icm42688_record_t last_record;
  /* INT1 */
  fake_icm42688_int1_t on_int1;
  void *int1_context;
  bool int1_high; /* latched mode level */
  uint32_t int1_edges;
  int64_t int1_last_edge_ns;
  /* failures on demand */
  bool absent;         /* every transfer NACKs */
  int32_t nack_after;  /* NACK the transfer after this many; -1 */
  bool stuck;          /* samples repeat the last one */
  float st_gyro_ratio; /* self-test response / factory one */
  float st_accel_ratio;
  /* what the test can check */
  uint32_t transfers;
  uint32_t timing_violations; /* writes lost in a wait the chip needs */
  uint32_t protocol_errors;   /* writes to read-only registers, bad bank */
  uint32_t soft_resets;
  fake_icm42688_record_t log[FAKE_ICM42688_LOG_SIZE];
  uint32_t log_head;
  uint32_t log_count;
  uint32_t log_dropped; /* records overwritten before taken */
} fake_icm42688_t;

/* A chip at `address` (0x68/0x69) just powered on, at fake time 0, clock exact. */
void fake_icm42688_init(fake_icm42688_t *const fake, uint8_t address);

/* A bus_t whose transfers, delays and timer go to `fake`. */
bus_t fake_icm42688_bus(fake_icm42688_t *const fake);

/* Runs the chip up to `time_ns` (no-op for a time already past): every ODR tick on the
 * way takes a sample, fills the FIFO and raises INT1 as the chip would. */
void fake_icm42688_advance_to_ns(fake_icm42688_t *const fake, int64_t time_ns);
void fake_icm42688_advance_us(fake_icm42688_t *const fake, uint32_t microseconds);

/* The next ODR tick on the fake's clock (INT64_MAX when the sensors are off). */
int64_t fake_icm42688_next_sample_ns(const fake_icm42688_t *const fake);

/* The node's timer now (what the bus's now_us returns). */
uint32_t fake_icm42688_timer_us(const fake_icm42688_t *const fake);

void fake_icm42688_set_source(fake_icm42688_t *const fake, fake_icm42688_source_t source,
                              void *context);
void fake_icm42688_set_int1(fake_icm42688_t *const fake, fake_icm42688_int1_t on_int1,
                            void *context);
/* Self-test trim codes (x, y, z) as the factory wrote them (0: none). */
void fake_icm42688_set_trim_codes(fake_icm42688_t *const fake, const uint8_t gyro[3],
                                  const uint8_t accel[3]);

/* The oldest packet read out of the FIFO and not yet taken; false when none. */
bool fake_icm42688_take_record(fake_icm42688_t *const fake, fake_icm42688_record_t *const record);

#endif /* FIRMWARE_TESTS_SUPPORT_FAKE_ICM42688_H */
