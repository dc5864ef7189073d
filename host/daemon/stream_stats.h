// What the host counts of one input stream over a Health period: messages received, messages
// lost (gaps in the sender's counter), malformed ones, and the transport latency.
#ifndef MOCAP_DAEMON_STREAM_STATS_H_
#define MOCAP_DAEMON_STREAM_STATS_H_

#include <cstdint>
#include <optional>
#include <vector>

#include "clock_watch.h"

namespace mocap {

struct StreamStats {
  uint64_t received_in_period = 0, lost = 0, invalid = 0;
  std::optional<uint64_t> last_counter;  // frame index / sequence / packet counter
  int64_t last_time_ns = 0;              // the sender's time of that message
  std::vector<double> latency_ms;        // arrival - sender's time, this period
  ClockWatch clock;                      // the sender's clock's steps (the caller checks)

  // Counts a message: its latency, and gaps in the sender's counter (lost messages; modulo 0
  // for a counter that does not wrap). A counter behind the last one is a late message when
  // the message is older too (it is no longer lost), a restart of the sender when it is
  // newer; a jump of 2^20 or more ahead is a restart too, not a loss.
  void Count(uint64_t counter, uint64_t modulo, int64_t time_ns, int64_t now_ns);
};

// The p-quantile (0 <= p <= 1) of v, by the nearest rank below; 0 when v is empty.
double Percentile(std::vector<double> v, double p);

}  // namespace mocap

#endif  // MOCAP_DAEMON_STREAM_STATS_H_
