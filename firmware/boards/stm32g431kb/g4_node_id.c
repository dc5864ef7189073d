/* Node id from the provisioning record or the unique device id (g4_node_id.h). */
#include "g4_node_id.h"

#define FNV1A_OFFSET 2166136261u
#define FNV1A_PRIME 16777619u

static bool g4_node_id_record_valid(const uint32_t record[G4_NODE_ID_RECORD_WORDS]) {
  return record[0] == G4_NODE_ID_MAGIC && record[2] == ~record[1] &&
         record[1] >= G4_NODE_ID_MIN && record[1] <= G4_NODE_ID_MAX;
}

static uint8_t g4_node_id_from_uid(const uint32_t uid[G4_NODE_ID_UID_WORDS]) {
  uint32_t hash = FNV1A_OFFSET;
  for (uint32_t word = 0u; word < G4_NODE_ID_UID_WORDS; word++) {
    for (uint32_t byte = 0u; byte < 4u; byte++) {
      hash ^= (uid[word] >> (8u * byte)) & 0xFFu;
      hash *= FNV1A_PRIME;
    }
  }
  return (uint8_t)(G4_NODE_ID_MIN + hash % (G4_NODE_ID_MAX - G4_NODE_ID_MIN + 1u));
}

g4_node_id_t g4_node_id_resolve(const uint32_t record[G4_NODE_ID_RECORD_WORDS],
                                const uint32_t uid[G4_NODE_ID_UID_WORDS]) {
  if (g4_node_id_record_valid(record)) {
    return (g4_node_id_t){.node_id = (uint8_t)record[1], .provisioned = true};
  }
  return (g4_node_id_t){.node_id = g4_node_id_from_uid(uid), .provisioned = false};
}
