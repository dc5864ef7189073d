// A stream's counts: lost messages from gaps in the sender's counter, across reordering,
// restarts and a wrapping counter; latency percentiles.
#include "stream_stats.h"

#include <gtest/gtest.h>

namespace mocap {
namespace {

constexpr int64_t kMs = 1'000'000;

TEST(StreamStats, GapsAreLostUntilTheLateMessageArrives) {
  StreamStats s;
  for (uint64_t counter : {0, 1, 4, 5}) s.Count(counter, 0, counter * 10 * kMs, counter * 10 * kMs);
  EXPECT_EQ(s.lost, 2u);              // 2 and 3
  s.Count(3, 0, 30 * kMs, 60 * kMs);  // late: older than the newest
  EXPECT_EQ(s.lost, 1u);
  EXPECT_EQ(s.received_in_period, 5u);
  EXPECT_EQ(*s.last_counter, 5u);
}

TEST(StreamStats, ACounterBackButTimeOnIsARestartNotALoss) {
  StreamStats s;
  s.Count(100, 0, 0, 0);
  s.Count(101, 0, kMs, kMs);
  s.Count(0, 0, 2 * kMs, 2 * kMs);  // the sender restarted
  s.Count(2, 0, 4 * kMs, 4 * kMs);  // one lost after the restart
  EXPECT_EQ(s.lost, 1u);
  s.Count(1u << 24, 0, 5 * kMs, 5 * kMs);  // a jump this far is a restart too
  EXPECT_EQ(s.lost, 1u);
}

TEST(StreamStats, AWrappingCounterCountsAcrossTheWrap) {
  StreamStats s;
  const uint64_t modulo = 1u << 16;
  s.Count(modulo - 2, modulo, 0, 0);
  s.Count(1, modulo, kMs, kMs);  // 65535 and 0 lost
  EXPECT_EQ(s.lost, 2u);
  s.Count(0, modulo, 0, 2 * kMs);  // one of them, late
  EXPECT_EQ(s.lost, 1u);
}

TEST(StreamStats, LatencyIsArrivalMinusTheSendersTime) {
  StreamStats s;
  for (int k = 0; k < 100; ++k) s.Count(k, 0, k * 10 * kMs, k * 10 * kMs + (k + 1) * kMs / 10);
  EXPECT_NEAR(Percentile(s.latency_ms, 0.5), 5.1, 1e-9);
  EXPECT_NEAR(Percentile(s.latency_ms, 0.99), 10.0, 1e-9);
  EXPECT_EQ(Percentile({}, 0.5), 0.0);
}

}  // namespace
}  // namespace mocap
