// A stream's clock steps: a sender's clock stepped by +1 s or -1 s is seen within kConfirmNs,
// counted with its return, and its messages refused meanwhile; a stall's backlog is no step; a
// step that lasts kRelearnNs is taken as the stream's clock.
#include "clock_watch.h"

#include <gtest/gtest.h>

namespace mocap {
namespace {

constexpr int64_t kMs = 1'000'000;
constexpr int64_t kPeriod = 16'666'667;  // 60 fps

// Feeds frames sent every period from `from` to `to` (arrival times, ns) whose sender's clock
// reads `step` off and which arrive `latency` after their time; how many were taken.
int Feed(ClockWatch* w, int64_t from, int64_t to, int64_t step, int64_t latency = 5 * kMs) {
  int taken = 0;
  for (int64_t t = from; t < to; t += kPeriod) taken += w->Check(t - latency + step, t);
  return taken;
}

TEST(ClockWatch, AStepForwardIsRefusedAtOnceCountedAndLeftWhenTheClockReturns) {
  ClockWatch w;
  EXPECT_EQ(Feed(&w, 0, 1000 * kMs, 0), 60);
  EXPECT_EQ(Feed(&w, 1000 * kMs, 2000 * kMs, 1000 * kMs), 0);  // from the future: never fused
  EXPECT_EQ(w.steps(), 1u);
  EXPECT_TRUE(w.off());
  EXPECT_EQ(Feed(&w, 2000 * kMs, 3000 * kMs, 0), 60);  // locked again
  EXPECT_EQ(w.steps(), 2u);
  EXPECT_FALSE(w.off());
  EXPECT_EQ(w.dropped(), 60u);
}

TEST(ClockWatch, AStepBackIsLeftToTheSynchroniserUntilConfirmedThenRefused) {
  ClockWatch w;
  Feed(&w, 0, 1000 * kMs, 0);
  const int taken = Feed(&w, 1000 * kMs, 2000 * kMs, -1000 * kMs);
  EXPECT_GE(taken, 6);  // the first kConfirmNs: late for the synchroniser, which counts them
  EXPECT_LE(taken, 7);
  EXPECT_EQ(w.steps(), 1u);
  Feed(&w, 2000 * kMs, 3000 * kMs, 0);
  EXPECT_EQ(w.steps(), 2u);
}

TEST(ClockWatch, AStallsBacklogIsNoStep) {
  ClockWatch w;
  Feed(&w, 0, 1000 * kMs, 0);
  // 500 ms of frames held up, then delivered within 5 ms, then on time again
  int taken = 0;
  for (int k = 0; k < 30; ++k) taken += w.Check(1000 * kMs + k * kPeriod, 1500 * kMs + k * kMs / 6);
  taken += Feed(&w, 1510 * kMs, 2500 * kMs, 0);
  EXPECT_EQ(taken, 30 + 60);
  EXPECT_EQ(w.steps(), 0u);
  EXPECT_EQ(w.dropped(), 0u);
}

TEST(ClockWatch, AStepThatLastsIsTakenAsTheClockAndAFutureFirstMessageIsRefused) {
  ClockWatch w;
  EXPECT_FALSE(w.Check(2000 * kMs, 1000 * kMs));  // a second from the future: nothing settled on it
  Feed(&w, 0, 1000 * kMs, 0);
  const int taken =
      Feed(&w, 1000 * kMs, 1000 * kMs + ClockWatch::kRelearnNs + 1000 * kMs, -2000 * kMs);
  EXPECT_GE(taken, 59);  // the last second's
  EXPECT_LE(taken, 68);
  EXPECT_FALSE(w.off());
  EXPECT_EQ(w.steps(), 1u);
}

// A box that starts by sending a second of queued frames at once, then on time: its offset
// settles on the backlog's and gives way to the on-time frames' without a step or a drop.
TEST(ClockWatch, AnOffsetSettledOnABacklogGivesWayToTimelyMessages) {
  ClockWatch w;
  int taken = 0;
  for (int k = 0; k < 60; ++k) taken += w.Check(k * kPeriod, 1000 * kMs + k * kMs / 10);
  taken += Feed(&w, 1100 * kMs, 3000 * kMs, 0);
  EXPECT_EQ(taken, 60 + 114);
  EXPECT_EQ(w.steps(), 0u);
  EXPECT_EQ(w.dropped(), 0u);
}

}  // namespace
}  // namespace mocap
