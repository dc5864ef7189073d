/* The node id (1..63) of a production node: a record in the last flash page, written when
 * the node is provisioned; without one, an id derived from the chip's unique id.
 *
 * The record (linker script: NODE_ID region, 0x0801F800, the last 2 KiB page of the
 * 128 KiB part, kept out of the image so reflashing the firmware keeps it) is three
 * little-endian words: G4_NODE_ID_MAGIC, the id, and the id's bitwise complement.
 * Erased flash (all ones), a wrong magic, a complement that does not match or an id
 * outside 1..63 make the record invalid. The fallback hashes the 96-bit unique device id
 * (FNV-1a) onto 1..63: two unprovisioned nodes may collide, so a suit's nodes are
 * provisioned (README.md says how).
 */
#ifndef FIRMWARE_BOARDS_STM32G431KB_G4_NODE_ID_H
#define FIRMWARE_BOARDS_STM32G431KB_G4_NODE_ID_H

#include <stdbool.h>
#include <stdint.h>

#define G4_NODE_ID_MAGIC 0x44494F4Eu /* "NOID" in flash byte order */
#define G4_NODE_ID_RECORD_WORDS 3u
#define G4_NODE_ID_UID_WORDS 3u
#define G4_NODE_ID_MIN 1u
#define G4_NODE_ID_MAX 63u

typedef struct {
  uint8_t node_id;     /* 1..63 */
  bool provisioned;    /* from the record (false: from the unique id) */
} g4_node_id_t;

g4_node_id_t g4_node_id_resolve(const uint32_t record[G4_NODE_ID_RECORD_WORDS],
                                const uint32_t uid[G4_NODE_ID_UID_WORDS]);

#endif /* FIRMWARE_BOARDS_STM32G431KB_G4_NODE_ID_H */
