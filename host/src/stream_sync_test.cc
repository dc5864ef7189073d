#include "mocap/stream_sync.h"

#include <gtest/gtest.h>

#include <cmath>

namespace mocap {
namespace {

constexpr int64_t kMs = 1'000'000;
constexpr int64_t kFrame = 16'666'667;  // 60 fps
constexpr int64_t kT0 = 1'763'900'000'000'000'000;

CameraInput Cam(int c, int64_t t, bool detected = true) {
  CameraInput in;
  in.camera = c;
  in.time_ns = t;
  in.detected = detected;
  in.keypoints.assign(3, Keypoint2D{100.0 + c, 200.0, 0.9});
  return in;
}

// An IMU turning about z at 1 rad/s with acceleration (t, 0, 9.81), t in s since kT0.
ImuInput Imu(int i, int64_t t) {
  ImuInput in;
  in.imu = i;
  in.time_ns = t;
  const double s = 1e-9 * static_cast<double>(t - kT0);
  in.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(s, Eigen::Vector3d::UnitZ()));
  in.acceleration = {s, 0, 9.81};
  return in;
}

TEST(StreamSync, ReleasesAFrameWhenEveryStreamHasDeliveredAndInterpolatesTheImu) {
  StreamSynchroniser sync(2, 1, SyncOptions{});
  const int64_t t = kT0 + 5 * kFrame;
  for (int64_t s = kT0; s <= t - 3 * kMs; s += 10 * kMs) sync.AddImu(Imu(0, s), s + kMs);
  sync.AddCamera(Cam(0, t), t + 2 * kMs);
  sync.AddCamera(Cam(1, t + kMs / 2), t + 3 * kMs);  // trigger skew within tolerance
  EXPECT_TRUE(sync.TakeReady(t + 3 * kMs).empty());  // the IMU has not reached t yet
  sync.AddImu(Imu(0, t + 7 * kMs), t + 8 * kMs);
  auto ready = sync.TakeReady(t + 8 * kMs);
  ASSERT_EQ(ready.size(), 1u);
  const SyncedFrame& f = ready[0];
  EXPECT_EQ(f.time_ns, t);
  EXPECT_EQ(f.last_input_ns, t + 8 * kMs);
  ASSERT_EQ(f.observations.cameras.size(), 2u);
  ASSERT_EQ(f.observations.imus.size(), 1u);
  const double s = 1e-9 * static_cast<double>(t - kT0);
  const Eigen::Quaterniond truth(Eigen::AngleAxisd(s, Eigen::Vector3d::UnitZ()));
  EXPECT_LT(f.observations.imus[0].orientation.angularDistance(truth),
            1e-9);  // slerp is exact here
  EXPECT_NEAR(f.observations.imus[0].acceleration.x(), s, 1e-9);
  EXPECT_EQ(sync.frames_forced(), 0u);
}

TEST(StreamSync, ACameraThatMissedAFrameDoesNotHoldItOnceItMovedOn) {
  StreamSynchroniser sync(2, 0, SyncOptions{});
  sync.AddCamera(Cam(0, kT0), kT0 + kMs);
  sync.AddCamera(Cam(1, kT0), kT0 + kMs);
  ASSERT_EQ(sync.TakeReady(kT0 + kMs).size(), 1u);
  sync.AddCamera(Cam(0, kT0 + kFrame), kT0 + kFrame + kMs);  // camera 1 drops this frame
  EXPECT_TRUE(sync.TakeReady(kT0 + kFrame + kMs).empty());
  sync.AddCamera(Cam(1, kT0 + 2 * kFrame), kT0 + 2 * kFrame + kMs);
  auto ready = sync.TakeReady(kT0 + 2 * kFrame + kMs);
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_EQ(ready[0].time_ns, kT0 + kFrame);
  ASSERT_EQ(ready[0].observations.cameras.size(), 1u);
  EXPECT_EQ(ready[0].observations.cameras[0].camera, 0);
  EXPECT_EQ(sync.frames_forced(), 0u);
}

TEST(StreamSync, DeadlineReleasesAFrameAStreamIsLateFor) {
  StreamSynchroniser sync(2, 0, SyncOptions{});
  sync.AddCamera(Cam(0, kT0), kT0 + kMs);
  sync.AddCamera(Cam(1, kT0), kT0 + kMs);
  sync.TakeReady(kT0 + kMs);
  sync.AddCamera(Cam(0, kT0 + kFrame), kT0 + kFrame + kMs);
  EXPECT_TRUE(sync.TakeReady(kT0 + kFrame + 24 * kMs).empty());
  EXPECT_EQ(sync.TakeReady(kT0 + kFrame + 25 * kMs).size(), 1u);
  EXPECT_EQ(sync.frames_forced(), 1u);
  // Camera 1's frame arrives after its frame was solved: late, dropped.
  sync.AddCamera(Cam(1, kT0 + kFrame), kT0 + kFrame + 30 * kMs);
  EXPECT_EQ(sync.camera_counts(1).late, 1u);
  EXPECT_EQ(sync.pending(), 0);
}

TEST(StreamSync, AStoppedCameraIsNotWaitedForAndCountsAgainWhenItReturns) {
  SyncOptions options;
  StreamSynchroniser sync(2, 0, options);
  int64_t t = kT0;
  for (int k = 0; k < 3; ++k, t += kFrame) {
    sync.AddCamera(Cam(0, t), t + kMs);
    sync.AddCamera(Cam(1, t), t + kMs);
    sync.TakeReady(t + kMs);
  }
  // Camera 1 unplugged: after stale_after its silence no longer delays frames.
  const int64_t stale = t + options.stale_after_ns + kFrame;
  for (; t < stale; t += kFrame) {
    sync.AddCamera(Cam(0, t), t + kMs);
    sync.TakeReady(t + kMs);
  }
  EXPECT_FALSE(sync.CameraActive(1, t));
  sync.AddCamera(Cam(0, t), t + kMs);
  auto ready = sync.TakeReady(t + kMs);  // at once, no deadline wait
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_EQ(ready[0].observations.cameras.size(), 1u);
  // Plugged back in: its frames join again.
  t += kFrame;
  sync.AddCamera(Cam(1, t), t + kMs);
  sync.AddCamera(Cam(0, t), t + kMs);
  ready = sync.TakeReady(t + kMs);
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_EQ(ready[0].observations.cameras.size(), 2u);
  EXPECT_TRUE(sync.CameraActive(1, t + kMs));
}

TEST(StreamSync, AStreamWhoseLinkWentDownIsNotWaitedForFromThatMoment) {
  StreamSynchroniser sync(2, 1, SyncOptions{});
  int64_t t = kT0;
  for (int k = 0; k < 3; ++k, t += kFrame) {
    sync.AddCamera(Cam(0, t), t + kMs);
    sync.AddCamera(Cam(1, t), t + kMs);
    sync.AddImu(Imu(0, t), t + kMs);
    ASSERT_EQ(sync.TakeReady(t + kMs).size(), 1u);
  }
  sync.AddCamera(Cam(0, t), t + kMs);
  sync.AddImu(Imu(0, t), t + kMs);
  EXPECT_TRUE(sync.TakeReady(t + 2 * kMs).empty());  // camera 1 is waited for
  sync.MarkLinkDown({1}, {});                        // its box's connection closed
  EXPECT_FALSE(sync.CameraActive(1, t + 2 * kMs));
  auto ready = sync.TakeReady(t + 2 * kMs);  // at once: no max_wait, no stale_after
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_EQ(ready[0].observations.cameras.size(), 1u);
  // The IMU's link down too: the next frame waits for neither.
  t += kFrame;
  sync.MarkLinkDown({}, {0});
  sync.AddCamera(Cam(0, t), t + kMs);
  ready = sync.TakeReady(t + kMs);
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_TRUE(ready[0].observations.imus.empty());
  // Back: each counts from its next input.
  t += kFrame;
  sync.AddCamera(Cam(1, t), t + kMs);
  sync.AddImu(Imu(0, t), t + kMs);
  EXPECT_TRUE(sync.CameraActive(1, t + kMs) && sync.ImuActive(0, t + kMs));
  sync.AddCamera(Cam(0, t), t + kMs);
  ready = sync.TakeReady(t + kMs);
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_EQ(ready[0].observations.cameras.size(), 2u);
}

TEST(StreamSync, OutOfOrderFramesAreReleasedInOrderAndDuplicatesDropped) {
  StreamSynchroniser sync(1, 0, SyncOptions{});
  sync.AddCamera(Cam(0, kT0 + kFrame), kT0 + kFrame);
  sync.AddCamera(Cam(0, kT0), kT0 + kFrame + kMs);
  sync.AddCamera(Cam(0, kT0), kT0 + kFrame + 2 * kMs);
  EXPECT_EQ(sync.camera_counts(0).duplicates, 1u);
  EXPECT_EQ(sync.camera_counts(0).out_of_order, 1u);
  auto ready = sync.TakeReady(kT0 + kFrame + 30 * kMs);
  ASSERT_EQ(ready.size(), 2u);
  EXPECT_EQ(ready[0].time_ns, kT0);
  EXPECT_EQ(ready[1].time_ns, kT0 + kFrame);
  EXPECT_LT(ready[0].observations.timestamp, ready[1].observations.timestamp);
}

TEST(StreamSync, FramesWithoutDetectionClockTheSolveWithoutKeypoints) {
  StreamSynchroniser sync(1, 1, SyncOptions{});
  for (int64_t s = kT0 - 20 * kMs; s <= kT0 + 20 * kMs; s += 10 * kMs) sync.AddImu(Imu(0, s), s);
  sync.AddCamera(Cam(0, kT0, /*detected=*/false), kT0 + 20 * kMs);
  auto ready = sync.TakeReady(kT0 + 20 * kMs);
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_TRUE(ready[0].observations.cameras.empty());
  EXPECT_EQ(ready[0].cameras_clocked, std::vector<int>{0});
  EXPECT_TRUE(ready[0].cameras_detected.empty());
  EXPECT_EQ(ready[0].observations.imus.size(), 1u);
}

TEST(StreamSync, AnImuWithoutNearbySamplesIsLeftOutAndAStoppedOneIsNotWaitedFor) {
  SyncOptions options;
  StreamSynchroniser sync(1, 2, options);
  // IMU 1 delivered long ago, then stopped; IMU 0 is live.
  sync.AddImu(Imu(1, kT0 - options.stale_after_ns), kT0 - options.stale_after_ns);
  for (int64_t s = kT0 - 20 * kMs; s <= kT0 + 10 * kMs; s += 10 * kMs) sync.AddImu(Imu(0, s), s);
  sync.AddCamera(Cam(0, kT0), kT0 + 11 * kMs);
  auto ready = sync.TakeReady(kT0 + 11 * kMs);
  ASSERT_EQ(ready.size(), 1u);
  ASSERT_EQ(ready[0].observations.imus.size(), 1u);
  EXPECT_EQ(ready[0].observations.imus[0].imu, 0);
}

TEST(StreamSync, WithoutCamerasTheImusClockTheFrames) {
  SyncOptions options;
  options.imu_only_rate_hz = 50;
  StreamSynchroniser sync(2, 1, options);
  std::vector<SyncedFrame> frames;
  // The cameras are expected for stale_after from the first input; then the IMUs clock.
  for (int64_t s = kT0; s <= kT0 + options.stale_after_ns + 200 * kMs; s += 5 * kMs) {
    sync.AddImu(Imu(0, s), s + kMs);
    for (auto& f : sync.TakeReady(s + kMs)) frames.push_back(std::move(f));
  }
  ASSERT_GE(frames.size(), 10u);
  for (size_t k = 1; k < frames.size(); ++k)
    EXPECT_EQ(frames[k].time_ns - frames[k - 1].time_ns, 20 * kMs);
  for (const auto& f : frames) EXPECT_EQ(f.observations.imus.size(), 1u);
}

TEST(StreamSync, AFlushHandsOverEveryPendingFrame) {
  StreamSynchroniser sync(2, 0, SyncOptions{});
  EXPECT_TRUE(sync.Flush().empty());
  // Camera 1 is expected but silent; camera 0's clock runs 100 ms ahead of the arrival clock,
  // so even max_wait after the last arrival its frames are not due.
  const int64_t arrival = kT0 - 100 * kMs;
  sync.AddCamera(Cam(0, kT0), arrival);
  sync.AddCamera(Cam(0, kT0 + kFrame), arrival);
  EXPECT_TRUE(sync.TakeReady(arrival + SyncOptions().max_wait_ns).empty());
  const std::vector<SyncedFrame> rest = sync.Flush();
  ASSERT_EQ(rest.size(), 2u);
  EXPECT_EQ(rest[0].time_ns, kT0);
  EXPECT_EQ(rest[1].time_ns, kT0 + kFrame);
  EXPECT_EQ(rest[1].released_ns, arrival + SyncOptions().max_wait_ns);
  EXPECT_EQ(sync.frames_forced(), 2u);
  EXPECT_EQ(sync.pending(), 0);
}

TEST(StreamSync, AnOverfullQueueHandsOverItsOldestFrame) {
  SyncOptions options;
  options.max_pending_frames = 4;
  StreamSynchroniser sync(2, 0, options);
  sync.AddCamera(Cam(1, kT0), kT0);          // camera 1 is active but never delivers again
  EXPECT_TRUE(sync.TakeReady(kT0).empty());  // camera 0 is expected too
  for (int k = 1; k <= 6; ++k) sync.AddCamera(Cam(0, kT0 + k * kFrame), kT0);  // clock stuck at kT0
  auto ready = sync.TakeReady(kT0);
  EXPECT_EQ(ready.size(), 3u);
  EXPECT_EQ(sync.pending(), 4);
}

}  // namespace
}  // namespace mocap
