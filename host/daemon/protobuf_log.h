// protobuf's runtime logs a line for each string field that is not UTF-8 when it parses a
// message (the message is then dropped as undecodable and counted by the pipeline). A sender
// of such messages would fill the host's log: the limiter lets one line through per interval
// and says, with the next, how many it held back.
#ifndef MOCAP_DAEMON_PROTOBUF_LOG_H_
#define MOCAP_DAEMON_PROTOBUF_LOG_H_

#include <chrono>
#include <cstdint>

namespace mocap::wire {

inline constexpr std::chrono::seconds kProtobufLogInterval{10};

// Routes protobuf's log through the limiter (idempotent; DecodeMessage calls it). A fatal
// line always goes out.
void LimitProtobufLog();

// protobuf log lines held back so far (for tests and the exit summary).
uint64_t ProtobufLogLinesHeldBack();

}  // namespace mocap::wire

#endif  // MOCAP_DAEMON_PROTOBUF_LOG_H_
