/* The mps2-an386's external interrupts: none is used, every one ends the run. */
#include "startup.h"

#define DEFAULT_8                                                                          \
  board_default_handler, board_default_handler, board_default_handler,                     \
      board_default_handler, board_default_handler, board_default_handler,                 \
      board_default_handler, board_default_handler

BOARD_IRQ_VECTORS const board_handler_t board_irq_vectors[48] = {
    DEFAULT_8, DEFAULT_8, DEFAULT_8, DEFAULT_8, DEFAULT_8, DEFAULT_8,
};
