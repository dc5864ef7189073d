/* ICM-42688-P: FIFO reads (count, overflow, burst, packet parsing) and data-ready. */
#include "icm42688.h"
#include "icm42688_internal.h"
#include "icm42688_regs.h"

#define ICM42688_FIFO_TEMP_LSB_PER_DEGC 2.07f   /* 8-bit FIFO temperature */
#define ICM42688_DATA_TEMP_LSB_PER_DEGC 132.48f /* 16-bit TEMP_DATA */
#define ICM42688_TEMP_OFFSET_DEGC 25.0f
#define ICM42688_READY_POLL_US 100u
#define ICM42688_READY_POLLS 10000u /* 1 s */
#define ICM42688_READ_ROUNDS 4u     /* FIFO_COUNT + burst rounds per read at most */

/* Flushes after an overflow or a corrupt packet: the packets left cannot be placed in
 * time any more. */
static icm42688_status_t icm42688_discard_fifo(icm42688_t *const dev, bool *const overflowed,
                                               icm42688_status_t reason) {
  *overflowed = true;
  dev->fifo_overflows++;
  const icm42688_status_t status = icm42688_flush_fifo(dev);
  dev->last_status = status != ICM42688_OK ? status : reason;
  return dev->last_status;
}

/* True when packets were lost since the last read (FIFO_FULL raised and a lost count). */
static icm42688_status_t icm42688_check_lost(icm42688_t *const dev, bool *const lost) {
  *lost = false;
  if ((dev->int_status & ICM42688_INT_STATUS_FIFO_FULL) == 0u) return ICM42688_OK;
  dev->int_status &= (uint8_t)~ICM42688_INT_STATUS_FIFO_FULL;
  uint8_t count[2] = {0u, 0u};
  const icm42688_status_t status =
      icm42688_read_registers(dev, 0u, ICM42688_REG_FIFO_LOST_PKT0, count, 2u);
  *lost = ((uint16_t)count[0] | (uint16_t)((uint16_t)count[1] << 8)) != 0u;
  return status;
}

/* One packet 3 to a sample; false when its header is not packet 3. */
static bool icm42688_parse_packet(const icm42688_t *const dev, const uint8_t *const packet,
                                  imu_sample_t *const sample) {
  const uint8_t kind = (uint8_t)(packet[0] & ICM42688_FIFO_HEADER_KIND_MASK);
  if (kind != ICM42688_FIFO_HEADER_PACKET3) return false;
  const float temp_degc =
      (float)(int8_t)packet[13] / ICM42688_FIFO_TEMP_LSB_PER_DEGC + ICM42688_TEMP_OFFSET_DEGC;
  icm42688_convert(dev, &packet[1], temp_degc, sample);
  return true;
}

/* Reads `n` packets in bursts; stops at the first corrupt one. */
static icm42688_status_t icm42688_read_packets(icm42688_t *const dev, imu_sample_t *const samples,
                                               size_t n, size_t *const count,
                                               bool *const overflowed) {
  while (*count < n) {
    size_t chunk = n - *count;
    if (chunk > ICM42688_READ_BURST_SAMPLES) chunk = ICM42688_READ_BURST_SAMPLES;
    const icm42688_status_t status = icm42688_read_registers(
        dev, 0u, ICM42688_REG_FIFO_DATA, dev->burst, chunk * ICM42688_FIFO_PACKET_BYTES);
    if (status != ICM42688_OK) return status;
    for (size_t i = 0; i < chunk; ++i) {
      if (!icm42688_parse_packet(dev, &dev->burst[i * ICM42688_FIFO_PACKET_BYTES],
                                 &samples[*count])) {
        return icm42688_discard_fifo(dev, overflowed, ICM42688_FIFO_CORRUPT);
      }
      ++*count;
    }
  }
  return ICM42688_OK;
}

/* One round: INT_STATUS and FIFO_COUNT, then up to `room` of the packets counted.
 * *available: the packets the FIFO held. */
static icm42688_status_t icm42688_read_round(icm42688_t *const dev, imu_sample_t *const samples,
                                             size_t room, size_t *const count,
                                             size_t *const available, bool *const overflowed) {
  uint8_t head[3]; /* INT_STATUS, FIFO_COUNTH, FIFO_COUNTL in one transfer */
  *available = 0u;
  icm42688_status_t status =
      icm42688_read_registers(dev, 0u, ICM42688_REG_INT_STATUS, head, sizeof(head));
  if (status != ICM42688_OK) return status;
  dev->int_status |= head[0];
  bool lost = false;
  status = icm42688_check_lost(dev, &lost);
  if (status != ICM42688_OK) return status;
  if (lost) return icm42688_discard_fifo(dev, overflowed, ICM42688_OK);
  *available = ((size_t)head[1] << 8) | head[2];
  if (*available > ICM42688_FIFO_CAPACITY_SAMPLES) {
    return icm42688_discard_fifo(dev, overflowed, ICM42688_FIFO_CORRUPT);
  }
  const size_t n = *available < room ? *available : room;
  size_t read = 0u;
  status = icm42688_read_packets(dev, samples, n, &read, overflowed);
  *count += read;
  return status;
}

icm42688_status_t icm42688_read_fifo(icm42688_t *const dev, imu_sample_t *const samples,
                                     size_t capacity, size_t *const count, bool *const overflowed) {
  *count = 0u;
  *overflowed = false;
  if (!dev->configured) return ICM42688_NOT_READY;
  /* Rounds while the FIFO held the watermark or more (packets written during a round are
   * read by the next), so the count ends below the watermark and the next edge comes;
   * at most ICM42688_READ_ROUNDS, for a bus barely faster than the chip. */
  icm42688_status_t status = ICM42688_OK;
  size_t available = dev->config.fifo_watermark_samples;
  for (uint32_t round = 0u; round < ICM42688_READ_ROUNDS && status == ICM42688_OK && !*overflowed &&
                            *count < capacity && available >= dev->config.fifo_watermark_samples;
       ++round) {
    status = icm42688_read_round(dev, &samples[*count], capacity - *count, count, &available,
                                 overflowed);
  }
  dev->last_status = status;
  return status;
}

icm42688_status_t icm42688_data_ready(icm42688_t *const dev, bool *const ready) {
  *ready = false;
  if (!dev->initialised) return ICM42688_NOT_READY;
  const icm42688_status_t status = icm42688_poll_int_status(dev);
  *ready = (dev->int_status & ICM42688_INT_STATUS_DATA_RDY) != 0u;
  dev->int_status &= (uint8_t)~ICM42688_INT_STATUS_DATA_RDY;
  return status;
}

icm42688_status_t icm42688_read_data(icm42688_t *const dev, imu_sample_t *const sample) {
  if (!dev->configured) return ICM42688_NOT_READY;
  uint8_t raw[14]; /* TEMP_DATA1..0, ACCEL x y z, GYRO x y z */
  const icm42688_status_t status =
      icm42688_read_registers(dev, 0u, ICM42688_REG_TEMP_DATA1, raw, sizeof(raw));
  if (status != ICM42688_OK) return status;
  const float temp_degc =
      (float)icm42688_be16(raw) / ICM42688_DATA_TEMP_LSB_PER_DEGC + ICM42688_TEMP_OFFSET_DEGC;
  icm42688_convert(dev, &raw[2], temp_degc, sample);
  return ICM42688_OK;
}

icm42688_status_t icm42688_read_raw_when_ready(icm42688_t *const dev, int16_t raw[6]) {
  for (uint32_t poll = 0u; poll < ICM42688_READY_POLLS; ++poll) {
    bool ready = false;
    icm42688_status_t status = icm42688_data_ready(dev, &ready);
    if (status != ICM42688_OK) return status;
    if (ready) {
      uint8_t bytes[12];
      status = icm42688_read_registers(dev, 0u, ICM42688_REG_ACCEL_DATA_X1, bytes, sizeof(bytes));
      if (status != ICM42688_OK) return status;
      for (size_t i = 0; i < 6u; ++i) raw[i] = icm42688_be16(&bytes[2u * i]);
      return ICM42688_OK;
    }
    icm42688_wait_us(dev, ICM42688_READY_POLL_US);
  }
  return ICM42688_TIMEOUT;
}
