/* Single-producer, single-consumer queue indices: the hand-over between an interrupt
 * (producer) and the main loop (consumer) on a single-core MCU. The producer writes only
 * `head`, the consumer only `tail`; each reads the other's with a volatile access, and
 * aligned 32-bit accesses are atomic on Cortex-M. Capacities are powers of two; the
 * indices run freely and wrap at 2^32. The element arrays live beside the indices in the
 * owner's struct (sized at compile time). A signal fence keeps the compiler from moving the
 * slot's contents across the index update (one core: no hardware barrier is needed).
 */
#ifndef FIRMWARE_CORE_NODE_QUEUE_H
#define FIRMWARE_CORE_NODE_QUEUE_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

typedef struct {
  volatile uint32_t head; /* written by the producer: next slot to fill */
  volatile uint32_t tail; /* written by the consumer: next slot to take */
  uint32_t dropped;       /* pushes refused because the queue was full (producer's count) */
} node_queue_t;

static inline uint32_t node_queue_count(const node_queue_t *const queue) {
  return queue->head - queue->tail;
}

/* The slot to fill (index into the array), or false when full (counted). Call
 * node_queue_commit after writing the slot. */
static inline bool node_queue_reserve(node_queue_t *const queue, uint32_t capacity,
                                      uint32_t *const slot) {
  if (queue->head - queue->tail >= capacity) {
    queue->dropped++;
    return false;
  }
  *slot = queue->head & (capacity - 1u);
  return true;
}

static inline void node_queue_commit(node_queue_t *const queue) {
  atomic_signal_fence(memory_order_release);
  queue->head = queue->head + 1u;
}

/* The oldest filled slot, or false when empty. Call node_queue_release after reading it. */
static inline bool node_queue_peek(const node_queue_t *const queue, uint32_t capacity,
                                   uint32_t *const slot) {
  if (queue->head == queue->tail) return false;
  atomic_signal_fence(memory_order_acquire);
  *slot = queue->tail & (capacity - 1u);
  return true;
}

static inline void node_queue_release(node_queue_t *const queue) {
  atomic_signal_fence(memory_order_release);
  queue->tail = queue->tail + 1u;
}

#endif /* FIRMWARE_CORE_NODE_QUEUE_H */
