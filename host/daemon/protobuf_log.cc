#include "protobuf_log.h"

#include <google/protobuf/stubs/logging.h>

#include <atomic>
#include <cstdio>
#include <mutex>
#include <string>

namespace mocap::wire {
namespace {

namespace pb = google::protobuf;

std::mutex g_mutex;
std::chrono::steady_clock::time_point g_last_line;  // epoch: nothing written yet
uint64_t g_held_since_last = 0;
std::atomic<uint64_t> g_held_total{0};

const char* LevelName(pb::LogLevel level) {
  switch (level) {
    case pb::LOGLEVEL_INFO:
      return "INFO";
    case pb::LOGLEVEL_WARNING:
      return "WARNING";
    case pb::LOGLEVEL_ERROR:
      return "ERROR";
    default:
      return "FATAL";
  }
}

void LimitedHandler(pb::LogLevel level, const char* filename, int line,
                    const std::string& message) {
  const auto now = std::chrono::steady_clock::now();
  std::lock_guard<std::mutex> lock(g_mutex);
  const bool first = g_last_line == std::chrono::steady_clock::time_point{};
  if (level != pb::LOGLEVEL_FATAL && !first && now - g_last_line < kProtobufLogInterval) {
    ++g_held_since_last;
    ++g_held_total;
    return;
  }
  std::string held;
  if (g_held_since_last > 0)
    held = " (" + std::to_string(g_held_since_last) +
           " more protobuf lines held back before this one)";
  std::fprintf(stderr, "[libprotobuf %s %s:%d] %s%s\n", LevelName(level), filename, line,
               message.c_str(), held.c_str());
  g_last_line = now;
  g_held_since_last = 0;
}

}  // namespace

void LimitProtobufLog() {
  static std::once_flag once;
  std::call_once(once, [] { pb::SetLogHandler(&LimitedHandler); });
}

uint64_t ProtobufLogLinesHeldBack() { return g_held_total.load(); }

}  // namespace mocap::wire
