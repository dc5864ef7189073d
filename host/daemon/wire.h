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
inline constexpr size_t kMaxPayload = 1 << 20;  // bytes

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
