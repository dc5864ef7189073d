/* The node's side of the CAN protocol (proto/can/mocap_imu.dbc, spec in proto/can/README.md):
 * the frames a node sends, packed from physical values, and the frames it receives,
 * checked and unpacked. Bit layouts come from the code cantools generates from the
 * database; this file adds identifiers (base + node id), clamping to each signal's
 * range, and validation of what arrives.
 */
#ifndef FIRMWARE_CORE_CAN_PROTOCOL_H
#define FIRMWARE_CORE_CAN_PROTOCOL_H

#include <stdbool.h>
#include <stdint.h>

#include "can_frame.h"
#include "mocap_imu.h" /* generated from proto/can/mocap_imu.dbc */
#include "node_config.h"

/* Identifiers (from the database): a node's messages are the base plus its id (1..63). */
#define CAN_ID_SYNC MOCAP_IMU_SYNC_FRAME_ID
#define CAN_BASE_IMU_QUAT MOCAP_IMU_IMU_QUAT_FRAME_ID
#define CAN_BASE_IMU_ACCEL MOCAP_IMU_IMU_ACCEL_FRAME_ID
#define CAN_BASE_SYNC_REPORT MOCAP_IMU_SYNC_REPORT_FRAME_ID
#define CAN_BASE_COMMAND_REPLY MOCAP_IMU_COMMAND_REPLY_FRAME_ID
#define CAN_BASE_COMMAND MOCAP_IMU_COMMAND_FRAME_ID
#define CAN_BASE_HEARTBEAT MOCAP_IMU_HEARTBEAT_FRAME_ID
#define CAN_NODE_ID_MASK 0x3Fu
#define CAN_NODE_ID_MIN 1u
#define CAN_NODE_ID_MAX 63u

typedef enum {
  CAN_COMMAND_START = 1,
  CAN_COMMAND_STOP = 2,
  CAN_COMMAND_SET_RATE = 3,
  CAN_COMMAND_SET_RANGES = 4,
  CAN_COMMAND_SET_MODE = 5,
} can_command_code_t;

typedef enum {
  CAN_RESULT_OK = 0,
  CAN_RESULT_UNKNOWN_COMMAND = 1,
  CAN_RESULT_BAD_LENGTH = 2,
  CAN_RESULT_BAD_VALUE = 3, /* decided by the node, which knows what its chips accept */
  CAN_RESULT_BUSY = 4,      /* also the node's: the command needs the node stopped */
} can_result_t;

typedef struct {
  uint8_t code;             /* can_command_code_t, or what arrived */
  uint16_t rate_hz;         /* SET_RATE */
  uint8_t acc_range_g;      /* SET_RANGES */
  uint16_t gyro_range_dps;  /* SET_RANGES */
  uint8_t mode;             /* SET_MODE: node_mode_t */
} can_command_t;

typedef struct {
  uint8_t command;          /* the code answered (0: none could be read) */
  can_result_t result;
  uint16_t rate_hz;         /* the configuration after the command */
  uint8_t acc_range_g;
  uint16_t gyro_range_dps;
  node_mode_t mode;
  bool running;
} can_reply_t;

/* Heartbeat status bits, in the order of the Heartbeat's one-bit signals. */
typedef enum {
  CAN_STATUS_IMU_NACK = 1u << 0,
  CAN_STATUS_MAG_NACK = 1u << 1,
  CAN_STATUS_FIFO_OVERFLOW = 1u << 2,
  CAN_STATUS_IMU_STUCK = 1u << 3,
  CAN_STATUS_MAG_STUCK = 1u << 4,
  CAN_STATUS_COMMAND_REFUSED = 1u << 5,
  CAN_STATUS_FRAME_MALFORMED = 1u << 6,
  CAN_STATUS_SELF_TEST_FAILED = 1u << 7,
  CAN_STATUS_ACC_CLIPPED = 1u << 8,
  CAN_STATUS_MAG_DISTURBED = 1u << 9,
  CAN_STATUS_TX_OVERFLOW = 1u << 10,
} can_status_bit_t;

typedef enum { CAN_STATE_BOOT = 0, CAN_STATE_IDLE = 1, CAN_STATE_RUNNING = 2, CAN_STATE_FAULT = 3 } can_state_t;
typedef enum { CAN_CHIP_NONE = 0, CAN_CHIP_ICM42688P = 1 } can_chip_t;

typedef struct {
  can_state_t state;
  node_mode_t mode;
  bool synced;              /* a Sync arrived in the last 2 s */
  can_chip_t chip;
  uint16_t rate_hz;
  uint16_t status;          /* can_status_bit_t, since the previous heartbeat */
  uint8_t error_count;      /* refused commands and malformed frames, wraps at 256 */
} can_heartbeat_t;

/* What a received frame is, for node `node_id`. */
typedef enum {
  CAN_RX_IGNORED = 0,  /* not addressed to this node, or not a message a node receives */
  CAN_RX_SYNC,
  CAN_RX_COMMAND,
  CAN_RX_MALFORMED,    /* addressed to this node (or Sync) with a wrong length */
} can_rx_kind_t;

/* The two frames of one output sample: ImuQuat then ImuAccel. */
void can_protocol_pack_sample(uint8_t node_id, const node_output_t *const output,
                              can_frame_t *const quat_frame, can_frame_t *const accel_frame);
void can_protocol_pack_heartbeat(uint8_t node_id, const can_heartbeat_t *const heartbeat,
                                 can_frame_t *const frame);
void can_protocol_pack_reply(uint8_t node_id, const can_reply_t *const reply,
                             can_frame_t *const frame);
void can_protocol_pack_sync_report(uint8_t node_id, uint8_t sync_seq, uint32_t rx_time_us,
                                   can_frame_t *const frame);

can_rx_kind_t can_protocol_classify(uint8_t node_id, const can_frame_t *const frame);
/* The sync counter of a Sync frame (classified CAN_RX_SYNC). */
uint8_t can_protocol_unpack_sync(const can_frame_t *const frame);
/* The command of a Command frame (classified CAN_RX_COMMAND); CAN_RESULT_OK or
 * CAN_RESULT_UNKNOWN_COMMAND. Values are checked by the node. */
can_result_t can_protocol_unpack_command(const can_frame_t *const frame,
                                         can_command_t *const command);

#endif /* FIRMWARE_CORE_CAN_PROTOCOL_H */
