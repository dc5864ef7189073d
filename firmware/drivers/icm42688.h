/* TDK InvenSense ICM-42688-P 6-axis IMU (gyroscope + accelerometer) behind a bus_t,
 * I2C at 7-bit address 0x68 (AD0 low) or 0x69 (AD0 high).
 *
 * What the driver sets up (datasheet DS-000347; the register map is icm42688_regs.h):
 *   - both sensors in low-noise mode at one ODR (25, 50, 100, 200, 500, 1000, 2000,
 *     4000 or 8000 Hz: the chip has no other rate between 25 Hz and 8 kHz, no 800 Hz),
 *     accelerometer +-2/4/8/16 g, gyroscope +-250/500/1000/2000 deg/s;
 *   - the FIFO in stream mode with packet 3 (16 bytes: header, accel, gyro, 8-bit
 *     temperature, 16-bit ODR timestamp), count and watermark in packets (FIFO_COUNT_REC),
 *     2048 bytes = 128 packets;
 *   - INT1 push-pull, active high, PULSED (100 us; 8 us at 4 kHz and above): one rising
 *     edge each time the FIFO count crosses the watermark from below (FIFO_WM_GT_TH = 0),
 *     so the edge time is the time the watermark-th packet was written. Nothing else is
 *     routed to INT1.
 * Units and signs of the samples: imu_sample.h. Sensitivity: 32768 LSB per full scale
 * (2048 LSB/g at 16 g, 16.384 LSB/(deg/s) at 2000 deg/s); a raw value at +-32767 (or the
 * chip's -32768) on an axis sets that sensor's clipped flag.
 *
 * Failures: every bus error comes back as a status (NACK: ICM42688_NACK; timeout or
 * controller fault: ICM42688_BUS_ERROR) and leaves the driver uninitialised, so the
 * next calls return ICM42688_NOT_READY until icm42688_init and icm42688_configure
 * succeed again (the node re-initialises on its next attempt). No call loops forever:
 * every wait on the chip is bounded.
 *
 * FIFO overflow: icm42688_read_fifo reports it (*overflowed), flushes the FIFO and
 * records the flush time (icm42688_t.fifo_flush_us), where the node restarts its
 * sample clock. icm42688_configure also flushes the FIFO and records that time.
 */
#ifndef FIRMWARE_DRIVERS_ICM42688_H
#define FIRMWARE_DRIVERS_ICM42688_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "bus.h"
#include "imu_sample.h"

#define ICM42688_ADDRESS_AD0_LOW 0x68u
#define ICM42688_ADDRESS_AD0_HIGH 0x69u
#define ICM42688_FIFO_CAPACITY_SAMPLES 128u /* 2048-byte FIFO / 16-byte packets */
#define ICM42688_WATERMARK_MAX_SAMPLES 120u /* leaves 8 packets of room above it */
#define ICM42688_READ_BURST_SAMPLES 16u     /* packets per bus transfer of the FIFO */
#define ICM42688_SELF_TEST_SAMPLES 200u     /* averaged per self-test phase, at 1 kHz */

typedef struct {
  uint16_t odr_hz;                 /* output data rate of both sensors, Hz */
  uint8_t acc_range_g;             /* accelerometer full scale: 2, 4, 8 or 16 g */
  uint16_t gyro_range_dps;         /* gyroscope full scale: 250, 500, 1000 or 2000 deg/s */
  uint16_t fifo_watermark_samples; /* INT1 edge at this many packets, 1..120 */
} icm42688_config_t;

/* 1000 Hz, +-16 g, +-2000 deg/s, watermark 10 packets (an edge every 10 ms). */
extern const icm42688_config_t icm42688_config_default;

typedef enum {
  ICM42688_OK = 0,
  ICM42688_NACK,         /* the chip did not acknowledge a transfer (absent, unpowered) */
  ICM42688_WRONG_ID,     /* WHO_AM_I is not 0x47: another chip at the address */
  ICM42688_BAD_CONFIG,   /* a setting outside the chip's tables (nothing was written) */
  ICM42688_BUS_ERROR,    /* the controller timed out or failed */
  ICM42688_NOT_READY,    /* not initialised / configured (or a transfer failed since) */
  ICM42688_TIMEOUT,      /* the chip never raised data-ready */
  ICM42688_FIFO_CORRUPT, /* a FIFO packet with an unexpected header: FIFO flushed */
} icm42688_status_t;

typedef struct {
  const bus_t *bus;
  uint8_t address;               /* 7-bit */
  bool initialised;              /* reset and identified since the last failure */
  bool configured;               /* sensors and FIFO running with `config` */
  uint8_t bank;                  /* selected register bank; 0xFF: unknown */
  uint8_t int_status;            /* INT_STATUS bits read but not yet handled */
  icm42688_config_t config;      /* the configuration applied last */
  float acc_mps2_per_lsb;        /* accelerometer resolution at `config`, m/s^2 */
  float gyr_rads_per_lsb;        /* gyroscope resolution at `config`, rad/s */
  uint32_t fifo_flush_us;        /* bus timer when the FIFO was last flushed, us */
  uint32_t fifo_overflows;       /* overflows reported since init */
  uint32_t bus_failures;         /* failed transfers since init */
  icm42688_status_t last_status; /* of the last call that talked to the chip */
  uint8_t burst[ICM42688_READ_BURST_SAMPLES * 16u]; /* FIFO bytes of one transfer */
} icm42688_t;

/* Binds the driver to `bus`/`address`, checks WHO_AM_I, soft-resets the chip (waits
 * 1 ms) and checks WHO_AM_I again. The chip is left in its reset state (sensors off). */
icm42688_status_t icm42688_init(icm42688_t *const dev, const bus_t *const bus, uint8_t address);

/* Validates `config` (ICM42688_BAD_CONFIG, nothing written, when outside the tables),
 * sets ranges, ODR, FIFO, watermark and INT1, powers the sensors (waits for the
 * gyroscope to start when they were off), then flushes the FIFO (fifo_flush_us). */
icm42688_status_t icm42688_configure(icm42688_t *const dev, const icm42688_config_t *const config);

/* Reads up to `capacity` samples from the FIFO, oldest first: FIFO_COUNT, then a burst
 * of the packets counted, again while the count was at or above the watermark (up to 4
 * rounds), so the FIFO ends below the watermark and its edge comes back (when the bus
 * is too slow for that, no edge comes: the node also reads after a timeout without one).
 * *overflowed is true when the FIFO lost packets since the last read: the FIFO is then
 * flushed (fifo_flush_us); the *count samples returned came before the loss. *count
 * samples are valid whatever the status. Call again while *count == capacity. */
icm42688_status_t icm42688_read_fifo(icm42688_t *const dev, imu_sample_t *const samples,
                                     size_t capacity, size_t *const count, bool *const overflowed);

/* Data-ready: a new sample reached the data registers since the last check. */
icm42688_status_t icm42688_data_ready(icm42688_t *const dev, bool *const ready);

/* The latest sample from the data registers (not the FIFO). */
icm42688_status_t icm42688_read_data(icm42688_t *const dev, imu_sample_t *const sample);

/* The datasheet's self-test with the factory trim codes: at +-250 deg/s, +-2 g, 1 kHz,
 * averages ICM42688_SELF_TEST_SAMPLES samples with the self-test actuation off and on,
 * per sensor; passes when every axis' response is 0.5..1.5 times the factory response
 * (2620 LSB * 1.01^(code-1); without codes, 60 deg/s minimum and 50..1200 mg) and
 * the gyroscope offset is below 20 deg/s. The chip must be still. Takes about 1 s.
 * Afterwards the last configuration is applied again (FIFO flushed) if there was one. */
icm42688_status_t icm42688_self_test(icm42688_t *const dev, bool *const passed);

/* True when the chip supports `odr_hz` (the list above). */
bool icm42688_odr_supported(uint16_t odr_hz);

/* The sample period of `odr_hz` in microseconds (0 when unsupported). */
uint32_t icm42688_odr_period_us(uint16_t odr_hz);

#endif /* FIRMWARE_DRIVERS_ICM42688_H */
