// The live host: subscribes to every edge box and IMU hub, feeds the pipeline, publishes
// PoseFrame and Health (ZeroMQ, bounded queues, reconnecting by itself).
#ifndef MOCAP_DAEMON_DAEMON_H_
#define MOCAP_DAEMON_DAEMON_H_

#include <atomic>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "pipeline.h"

namespace mocap {

struct DaemonOptions {
  double duration_s = 0;         // stop after this long; 0 = until stopped
  double health_period_s = 1.0;  // Health messages
  bool log_health = true;        // one line per Health on stderr
};

struct DaemonSummary {
  uint64_t frames = 0;
  std::vector<double> latency_ms;  // every published frame's
  std::map<std::string, uint64_t> dropped;
  std::map<std::string, uint64_t> refused;  // per input endpoint: handshakes refused
  uint64_t subscribers_refused = 0;         // clients refused on the output (session "subscribers")
};

// Runs until *stop or the duration. Returns false and sets *error when a socket cannot be
// set up (bad endpoint, port taken).
bool RunDaemon(HostPipeline* pipeline, const DaemonOptions& options, const std::atomic<bool>* stop,
               DaemonSummary* summary, std::string* error);

int64_t NowNs();  // the shared timebase of this machine (CLOCK_REALTIME)

}  // namespace mocap

#endif  // MOCAP_DAEMON_DAEMON_H_
