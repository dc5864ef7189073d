// Drops counted by reason, and the Health message: one entry per stream with its rate,
// losses and drops, the calibrations, every message dropped before a stream, the poses.
#include "stream_monitor.h"

#include <gtest/gtest.h>

namespace mocap {
namespace {

constexpr int64_t kMs = 1'000'000;

const v1::StreamHealth& Stream(const v1::Health& h, const std::string& name) {
  for (const v1::StreamHealth& s : h.streams()) {
    if (s.stream() == name) return s;
  }
  ADD_FAILURE() << "no stream " << name;
  return h.streams(0);
}

TEST(StreamMonitor, ADropIsCountedByReasonAndSaysWhy) {
  StreamMonitor m({"cam0"}, {});
  std::string why;
  EXPECT_FALSE(m.Drop("undecodable", "3 bytes", &why));
  EXPECT_EQ(why, "undecodable: 3 bytes");
  EXPECT_FALSE(m.Drop("undecodable", "4 bytes", nullptr));
  m.CountDropped("late_or_duplicate", 2);
  EXPECT_EQ(m.dropped().at("undecodable"), 2u);
  EXPECT_EQ(m.dropped().at("late_or_duplicate"), 2u);
}

TEST(StreamMonitor, HealthReportsEachStreamOverThePeriod) {
  StreamMonitor m({"cam0", "cam1"}, {"wrist"});
  StreamSynchroniser sync(2, 1, SyncOptions());
  const int64_t t0 = 1'000'000 * kMs;
  HealthInputs in;
  in.sync = &sync;
  in.headings = {M_PI / 180};
  in.distrusted = {true};
  in.calibrations = {2, 3, 4};
  in.calibration_active = true;
  in.frames_solved = 7;
  in.frames_failed = 2;  // poses the solver refused
  m.Health(t0, in);      // starts the period
  for (int k = 0; k < 50; ++k) {
    if (k != 20) m.camera(0).Count(k, 0, t0 + k * kMs, t0 + k * kMs);  // frame 20 lost
  }
  m.camera(1).invalid = 1;
  m.hub("hub0").Count(0, 0, t0, t0 + 2 * kMs);
  m.Drop("undecodable", "", nullptr);
  m.Drop("invalid_calibration", "", nullptr);  // counted by the calibration stream
  for (int k = 0; k < 5; ++k) m.CountSolvedFrame();
  m.RecordLatency(4.0);
  const v1::Health h = m.Health(t0 + 500 * kMs, in);
  EXPECT_EQ(h.streams(0).stream(), "camera/cam0");
  EXPECT_NEAR(Stream(h, "camera/cam0").rate_hz(), 98.0, 1e-9);  // 49 in 0.5 s
  EXPECT_EQ(Stream(h, "camera/cam0").lost(), 1u);
  EXPECT_EQ(Stream(h, "camera/cam1").malformed(), 1u);
  EXPECT_EQ(Stream(h, "camera/cam1").dropped(), 1u);
  EXPECT_NEAR(Stream(h, "imu/wrist").heading_correction_deg(), 1.0, 1e-12);
  EXPECT_TRUE(Stream(h, "imu/wrist").distrusted());
  EXPECT_NEAR(Stream(h, "hub/hub0").latency_p50_ms(), 2.0, 1e-12);
  const v1::StreamHealth& calibration = Stream(h, "calibration");
  EXPECT_EQ(calibration.received(), 2u);
  EXPECT_EQ(calibration.malformed(), 3u);
  EXPECT_EQ(calibration.duplicates(), 4u);
  EXPECT_EQ(calibration.dropped(), 3u);  // repeats are not drops
  EXPECT_TRUE(calibration.active());
  EXPECT_EQ(Stream(h, "input").malformed(), 1u);
  EXPECT_NEAR(Stream(h, "pose").rate_hz(), 10.0, 1e-9);
  EXPECT_EQ(Stream(h, "pose").received(), 7u);
  EXPECT_EQ(h.frames_dropped(), 2u);
  EXPECT_EQ(h.latency_p50_ms(), 4.0);
  // The next period starts anew.
  const v1::Health next = m.Health(t0 + 1000 * kMs, in);
  EXPECT_EQ(Stream(next, "camera/cam0").rate_hz(), 0.0);
  EXPECT_EQ(Stream(next, "pose").rate_hz(), 0.0);
  EXPECT_EQ(next.latency_p50_ms(), 0.0);
}

}  // namespace
}  // namespace mocap
