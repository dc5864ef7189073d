// The mocap.v1 messages on ZeroMQ: [full type name, payload] (proto/README.md).
// DecodeMessage never throws: a message that cannot be used comes back with a drop reason.
#ifndef MOCAP_DAEMON_WIRE_H_
#define MOCAP_DAEMON_WIRE_H_

#include <google/protobuf/message.h>

#include <memory>
#include <string>
#include <string_view>

namespace mocap::wire {

inline constexpr std::string_view kVersion = "mocap.v1";
// Caps on what one message may hold (docs/reliability.md, "Fuzzing"): a payload's size bounds
// what parsing it allocates; the counts bound the work each message makes downstream.
inline constexpr size_t kMaxPayload = 1 << 20;  // bytes
inline constexpr int kMaxPersons = 32;          // per KeypointFrame (an edge box sends <= 2)
inline constexpr int kMaxKeypoints = 256;       // per person (the largest layout has 33)
inline constexpr int kMaxSamples = 4096;        // per ImuBatch (a hub's 10 ms batch: <= 300)
inline constexpr int kMaxStreams = 1024;        // per Health

enum class DropReason {
  kNone,
  kUnknownType,
  kWrongVersion,
  kOversized,
  kUndecodable,
  kNotFinite,
  kInvalid
};
const char* ToString(DropReason reason);

struct Decoded {
  std::unique_ptr<google::protobuf::Message> message;  // null when dropped
  DropReason reason = DropReason::kNone;
  std::string detail;  // what was wrong, for the log line
};

// Decodes and checks one message: known type of this version, size, parse, finite values,
// consistent lengths, required ids.
Decoded DecodeMessage(std::string_view type, std::string_view payload);

// The type frame of a message.
std::string TypeName(const google::protobuf::Message& message);

}  // namespace mocap::wire

#endif  // MOCAP_DAEMON_WIRE_H_
