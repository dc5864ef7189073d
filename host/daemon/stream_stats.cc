#include "stream_stats.h"

#include <algorithm>

namespace mocap {

void StreamStats::Count(uint64_t counter, uint64_t modulo, int64_t time_ns, int64_t now_ns) {
  constexpr uint64_t kLargestGap = 1u << 20;
  received_in_period++;
  // in doubles: a time from anywhere in int64's range (a broken sender) must not overflow
  latency_ms.push_back(1e-6 * (static_cast<double>(now_ns) - static_cast<double>(time_ns)));
  if (!last_counter) {
    last_counter = counter;
    last_time_ns = time_ns;
    return;
  }
  const uint64_t last = *last_counter;
  const uint64_t ahead = modulo ? (counter + modulo - last) % modulo : counter - last;
  const bool forward = modulo ? ahead != 0 && ahead < modulo / 2 : counter > last;
  if (forward) {
    if (ahead > 1 && ahead < kLargestGap) lost += ahead - 1;
  } else if (time_ns <= last_time_ns) {
    if (lost > 0) lost--;  // a late message, counted lost when it was skipped
    return;
  }  // else: newer but counted back: the sender restarted its counter
  last_counter = counter;
  last_time_ns = time_ns;
}

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(p * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

}  // namespace mocap
