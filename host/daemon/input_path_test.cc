// The input path on wire messages rendered from a synthetic studio: the subject's keypoints
// and the IMU readings reach synchronised frames, bad messages are dropped under their reason,
// the end of the input releases every pending frame, and frames a box did not detect on clock
// the solve without keypoints and are told apart from detected ones.
#include "input_path.h"

#include <gtest/gtest.h>

#include <limits>

#include "mocap/v1/health.pb.h"
#include "synthetic_scene.h"

namespace mocap {
namespace {

constexpr int64_t kT0 = 1'763'900'000'000'000'000;
constexpr int64_t kFrame = 16'666'667;
constexpr int64_t kMs = 1'000'000;
constexpr double kMinConfidence = 0.05;

struct Studio {
  testing::Scene scene = testing::MakeScene(2);
  Eigen::VectorXd pose;
  FrameObservations truth;
  Studio() {
    std::mt19937 rng(7);
    pose = testing::RandomPose(scene.skeleton, &rng, 0.3);
    truth = testing::Render(scene, pose, 0);
  }
  InputPath Path() const {
    return InputPath(scene.rig, scene.imus, scene.layout, SyncOptions(), kMinConfidence);
  }
  // Camera c's frame k: the subject, and a bystander `decoy_px` to the right (0: none).
  v1::KeypointFrame Keypoints(int k, int c, double decoy_px = 0, bool detected = true) const {
    v1::KeypointFrame f;
    f.set_camera_id(scene.rig.cameras[c].name);
    f.set_frame_index(k);
    f.set_capture_time_ns(kT0 + k * kFrame);
    f.set_keypoint_layout(scene.layout.name);
    f.set_detected(detected);
    if (!detected) return f;
    v1::KeypointPerson* decoy = decoy_px > 0 ? f.add_persons() : nullptr;
    v1::KeypointPerson* p = f.add_persons();
    for (const Keypoint2D& kp : truth.cameras[c].keypoints) {
      p->add_x(kp.x), p->add_y(kp.y), p->add_confidence(0.8f);
      if (decoy) decoy->add_x(kp.x + decoy_px), decoy->add_y(kp.y), decoy->add_confidence(1.0f);
    }
    return f;
  }
  // Every IMU's sample at frame k (the pose's orientations), plus `stranger`'s if named.
  v1::ImuBatch Imus(int k, const std::string& stranger = "") const {
    v1::ImuBatch b;
    b.set_hub_id("hub0");
    b.set_sequence(k);
    for (const ImuObservation& o : truth.imus) {
      v1::ImuSample* s = b.add_samples();
      s->set_sensor_id(scene.imus[o.imu].name);
      s->set_sample_time_ns(kT0 + k * kFrame);
      s->set_qw(o.orientation.w()), s->set_qx(o.orientation.x()), s->set_qy(o.orientation.y()),
          s->set_qz(o.orientation.z());
      s->set_ax(1), s->set_ay(2), s->set_az(3);
      s->set_packet_counter(k);
    }
    if (!stranger.empty()) b.add_samples()->set_sensor_id(stranger);
    return b;
  }
};

bool Feed(InputPath* path, const google::protobuf::Message& m, int64_t now,
          std::string* why = nullptr) {
  return path->Feed(m.GetDescriptor()->full_name(), m.SerializeAsString(), now, nullptr, why);
}

TEST(InputPath, TheSubjectsKeypointsAndTheImuReadingsMakeAFrame) {
  const Studio studio;
  InputPath path = studio.Path();
  const int64_t now = kT0 + 2 * kMs;
  ASSERT_TRUE(Feed(&path, studio.Imus(0), now));
  ASSERT_TRUE(Feed(&path, studio.Keypoints(0, 0), now));
  ASSERT_TRUE(Feed(&path, studio.Keypoints(0, 1), now));
  const std::vector<SyncedFrame> frames = path.TakeReady(now);
  ASSERT_EQ(frames.size(), 1u);
  const SyncedFrame& f = frames[0];
  EXPECT_EQ(f.time_ns, kT0);
  EXPECT_EQ(f.cameras_clocked, (std::vector<int>{0, 1}));
  EXPECT_EQ(f.cameras_detected, (std::vector<int>{0, 1}));
  ASSERT_EQ(f.observations.cameras.size(), 2u);
  for (const CameraObservation& o : f.observations.cameras) {
    const std::vector<Keypoint2D>& truth = studio.truth.cameras[o.camera].keypoints;
    ASSERT_EQ(o.keypoints.size(), truth.size());
    for (size_t k = 0; k < truth.size(); ++k) {
      EXPECT_NEAR(o.keypoints[k].x, truth[k].x, 1e-3) << o.camera << " " << k;  // float on wire
      EXPECT_NEAR(o.keypoints[k].confidence, 0.8, 1e-6);
    }
  }
  ASSERT_EQ(f.observations.imus.size(), studio.scene.imus.size());
  for (const ImuObservation& o : f.observations.imus) {
    EXPECT_LT(o.orientation.angularDistance(studio.truth.imus[o.imu].orientation), 1e-6);
    EXPECT_EQ(o.acceleration, Eigen::Vector3d(1, 2, 3));
  }
  EXPECT_TRUE(path.monitor().dropped().empty());
}

TEST(InputPath, BadMessagesAreDroppedUnderTheirReason) {
  const Studio studio;
  InputPath path = studio.Path();
  int64_t now = kT0 + kMs;
  std::string why;
  EXPECT_FALSE(path.Feed("mocap.v1.KeypointFrame", "\x12\x34garbage", now, nullptr, &why));
  EXPECT_EQ(why.rfind("undecodable: ", 0), 0u) << why;
  EXPECT_FALSE(path.Feed("mocap.v2.KeypointFrame", "", now, nullptr, &why));
  v1::KeypointFrame nan = studio.Keypoints(0, 0);
  nan.mutable_persons(0)->set_y(2, NAN);
  EXPECT_FALSE(Feed(&path, nan, now));
  v1::KeypointFrame stranger = studio.Keypoints(0, 0);
  stranger.set_camera_id("cam99");
  EXPECT_FALSE(Feed(&path, stranger, now, &why));
  EXPECT_NE(why.find("cam99"), std::string::npos) << why;
  v1::KeypointFrame other_layout = studio.Keypoints(0, 0);
  other_layout.set_keypoint_layout("coco17");
  EXPECT_FALSE(Feed(&path, other_layout, now));
  EXPECT_FALSE(Feed(&path, v1::Health(), now, &why));
  EXPECT_EQ(why.rfind("not_an_input: ", 0), 0u) << why;
  // Three samples of sensors not in the set: the batch's others are kept.
  v1::ImuBatch batch = studio.Imus(0, "stranger");
  *batch.add_samples() = batch.samples(batch.samples_size() - 1);
  *batch.add_samples() = batch.samples(batch.samples_size() - 1);
  EXPECT_FALSE(Feed(&path, batch, now));
  ASSERT_TRUE(Feed(&path, studio.Keypoints(0, 0), now));
  ASSERT_TRUE(Feed(&path, studio.Keypoints(0, 1), now));
  ASSERT_EQ(path.TakeReady(now).size(), 1u);
  EXPECT_FALSE(Feed(&path, studio.Keypoints(0, 1), now, &why));  // its frame is gone: late
  EXPECT_EQ(why.rfind("late_or_duplicate: ", 0), 0u) << why;
  EXPECT_TRUE(Feed(&path, studio.Imus(0), now));  // every sample a duplicate, counted each
  const std::map<std::string, uint64_t> expected = {
      {"undecodable", 1},
      {"wrong_version", 1},
      {"not_finite", 1},
      {"unknown_source", 4},
      {"invalid", 1},
      {"not_an_input", 1},
      {"late_or_duplicate", 1 + studio.scene.imus.size()}};
  EXPECT_EQ(path.monitor().dropped(), expected);
  EXPECT_EQ(path.sync().camera_counts(1).late, 1u);
  EXPECT_EQ(path.sync().imu_counts(0).duplicates, 1u);
}

TEST(InputPath, TheEndOfTheInputReleasesEveryPendingFrame) {
  const Studio studio;
  InputPath path = studio.Path();
  EXPECT_TRUE(path.Flush().empty());  // before any input
  // Camera 1 stops after frame 2; camera 0 and the IMUs deliver frames 0-4.
  for (int k = 0; k < 5; ++k) {
    const int64_t now = kT0 + k * kFrame + kMs;
    Feed(&path, studio.Imus(k), now);
    for (int c = 0; c < (k <= 2 ? 2 : 1); ++c) Feed(&path, studio.Keypoints(k, c), now);
    ASSERT_EQ(path.TakeReady(now).size(), k <= 2 ? 1u : 0u) << k;
  }
  const std::vector<SyncedFrame> rest = path.Flush();
  ASSERT_EQ(rest.size(), 2u);
  EXPECT_EQ(rest[0].time_ns, kT0 + 3 * kFrame);
  EXPECT_EQ(rest[1].time_ns, kT0 + 4 * kFrame);
  // Released at the live deadline after the last input, with what they had.
  EXPECT_EQ(rest[1].released_ns, kT0 + 4 * kFrame + kMs + SyncOptions().max_wait_ns);
  EXPECT_EQ(rest[1].cameras_clocked, std::vector<int>{0});
  EXPECT_EQ(rest[1].observations.imus.size(), studio.scene.imus.size());
  EXPECT_EQ(path.sync().pending(), 0);
  EXPECT_TRUE(path.Flush().empty());
}

TEST(InputPath, AFrameNotDetectedClocksTheSolveAndIsToldApart) {
  const Studio studio;
  InputPath path = studio.Path();
  const int64_t now = kT0 + 2 * kMs;
  Feed(&path, studio.Imus(0), now);
  Feed(&path, studio.Keypoints(0, 0), now);
  ASSERT_TRUE(Feed(&path, studio.Keypoints(0, 1, 0, /*detected=*/false), now));
  std::vector<SyncedFrame> frames = path.TakeReady(now);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].cameras_clocked, (std::vector<int>{0, 1}));
  EXPECT_EQ(frames[0].cameras_detected, std::vector<int>{0});
  ASSERT_EQ(frames[0].observations.cameras.size(), 1u);
  EXPECT_EQ(frames[0].observations.cameras[0].camera, 0);
  // Detection ran and found nobody: detected, without keypoints.
  v1::KeypointFrame nobody = studio.Keypoints(1, 1);
  nobody.clear_persons();
  Feed(&path, studio.Imus(1), now + kFrame);
  Feed(&path, studio.Keypoints(1, 0, 0, /*detected=*/false), now + kFrame);
  Feed(&path, nobody, now + kFrame);
  frames = path.TakeReady(now + kFrame);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].cameras_clocked, (std::vector<int>{0, 1}));
  EXPECT_EQ(frames[0].cameras_detected, std::vector<int>{1});
  EXPECT_TRUE(frames[0].observations.cameras.empty());
}

// Camera c's frame k with a bystander 40 px to the right, larger and more confident.
v1::KeypointFrame WithBystander(const Studio& studio, int k, int c) {
  v1::KeypointFrame f = studio.Keypoints(k, c, 40);
  f.mutable_persons(0)->set_y(0, f.persons(0).y(0) - 200);
  return f;
}

// The x of each camera's first keypoint in the frames released at now: whose they are.
std::vector<double> FirstKeypointX(InputPath* path, int64_t now) {
  std::vector<double> x;
  for (const SyncedFrame& f : path->TakeReady(now)) {
    for (const CameraObservation& o : f.observations.cameras) x.push_back(o.keypoints[0].x);
  }
  return x;
}

TEST(InputPath, EachCameraFollowsItsSubjectPastABystander) {
  const Studio studio;
  InputPath path = studio.Path();
  const std::vector<double> subject = {studio.truth.cameras[0].keypoints[0].x,
                                       studio.truth.cameras[1].keypoints[0].x};
  for (int k = 0; k < 3; ++k) {
    const int64_t now = kT0 + k * kFrame + kMs;
    Feed(&path, studio.Imus(k), now);
    for (int c = 0; c < 2; ++c)
      Feed(&path, k == 0 ? studio.Keypoints(k, c) : WithBystander(studio, k, c), now);
    const std::vector<double> x = FirstKeypointX(&path, now);
    ASSERT_EQ(x.size(), 2u) << k;
    for (int c = 0; c < 2; ++c) EXPECT_NEAR(x[c], subject[c], 1e-3) << k << " " << c;
  }
}

TEST(InputPath, TheTrackersPoseChoosesTheSubject) {
  const Studio studio;
  std::string error;
  auto tracker = Solver::Create(studio.scene.skeleton, studio.scene.rig, studio.scene.layout,
                                studio.scene.imus, std::nullopt, SolverOptions(), &error);
  ASSERT_TRUE(tracker) << error;
  tracker->Solve(studio.truth);
  ASSERT_TRUE(tracker->initialised());
  for (const Solver* t : std::vector<const Solver*>{nullptr, tracker.get()}) {
    InputPath path = studio.Path();
    const int64_t now = kT0 + kMs;
    Feed(&path, studio.Imus(0), now);
    for (int c = 0; c < 2; ++c) {
      const std::string payload = WithBystander(studio, 0, c).SerializeAsString();
      ASSERT_TRUE(path.Feed("mocap.v1.KeypointFrame", payload, now, t, nullptr));
    }
    const std::vector<double> x = FirstKeypointX(&path, now);
    ASSERT_EQ(x.size(), 2u);
    for (int c = 0; c < 2; ++c) {  // without a tracker (or memory), the larger bystander
      const double expected = studio.truth.cameras[c].keypoints[0].x + (t ? 0 : 40);
      EXPECT_NEAR(x[c], expected, 1e-3) << c;
    }
  }
}

// A recording replayed without moving its times to now: its inputs are an hour older than
// their arrival. Each is dropped as clock_offset, so no frame is released on one camera.
TEST(InputPath, InputsOnAnotherClockThanTheArrivalAreDropped) {
  const Studio studio;
  InputPath path = studio.Path();
  const int64_t hour = 3'600'000'000'000;
  std::string why;
  EXPECT_FALSE(Feed(&path, studio.Keypoints(0, 0), kT0 + hour, &why));
  EXPECT_EQ(
      why.rfind("clock_offset: " + studio.scene.rig.cameras[0].name + " frame 0 captured 3600", 0),
      0u)
      << why;
  EXPECT_FALSE(Feed(&path, studio.Imus(0), kT0 - hour, &why));  // ahead of the host: refused too
  EXPECT_NE(why.find("samples of hub hub0"), std::string::npos) << why;
  EXPECT_TRUE(path.TakeReady(kT0 + hour).empty());
  EXPECT_EQ(path.monitor().dropped().at("clock_offset"), 1 + studio.scene.imus.size());
  // Late by 9 s (a host far behind): late, but on the host's clock, so taken.
  EXPECT_TRUE(Feed(&path, studio.Keypoints(1, 0), kT0 + kFrame + 9000 * kMs));
  // Times at the ends of int64's range (found by fuzz_wire: the latency and the offset
  // overflowed): refused, on every path.
  for (const int64_t t :
       {std::numeric_limits<int64_t>::min(), std::numeric_limits<int64_t>::max()}) {
    v1::KeypointFrame frame = studio.Keypoints(2, 0);
    frame.set_capture_time_ns(t);
    EXPECT_FALSE(Feed(&path, frame, kT0, &why));
    EXPECT_EQ(why.rfind("clock_offset", 0), 0u) << why;
    v1::ImuBatch batch = studio.Imus(2);
    batch.set_send_time_ns(t);
    for (v1::ImuSample& sample : *batch.mutable_samples()) sample.set_sample_time_ns(t);
    EXPECT_FALSE(Feed(&path, batch, kT0, &why));
  }
}

// Camera 1's clock steps +1 s for 1 s (a PTP loss), then -1 s for 1 s: its frames are refused
// while the others' still make a frame each, waiting for it no longer than for a box gone
// silent (max_wait, seen at the next frame's poll); Health counts the three steps.
TEST(InputPath, ACameraWhoseClockStepsIsLeftOutWithoutHoldingTheOthers) {
  const Studio studio;
  InputPath path = studio.Path();
  int frames = 0, with_camera1 = 0;
  for (int k = 0; k < 240; ++k) {
    const int64_t now = kT0 + k * kFrame + 5 * kMs;
    const int64_t step = k >= 60 && k < 120    ? 1'000'000'000
                         : k >= 120 && k < 180 ? -1'000'000'000
                                               : 0;
    Feed(&path, studio.Imus(k), now);
    Feed(&path, studio.Keypoints(k, 0), now);
    v1::KeypointFrame stepped = studio.Keypoints(k, 1);
    stepped.set_capture_time_ns(stepped.capture_time_ns() + step);
    Feed(&path, stepped, now);
    for (const SyncedFrame& f : path.TakeReady(now)) {
      frames++;
      with_camera1 += f.cameras_clocked.size() == 2;
      EXPECT_LE(f.released_ns - f.time_ns, 5 * kMs + SyncOptions().max_wait_ns + kFrame);
    }
  }
  EXPECT_GE(frames, 238);
  EXPECT_GE(with_camera1, 120 - 2);  // before and after the steps
  EXPECT_LE(with_camera1, 120 + 8);  // and the step back's first frames, late for their own time
  HealthInputs in;
  in.sync = &path.sync();
  in.headings.assign(studio.scene.imus.size(), 0.0);
  const v1::Health h = path.monitor().Health(kT0 + 241 * kFrame, in);
  const v1::StreamHealth& camera1 = h.streams(1);
  EXPECT_EQ(camera1.stream(), "camera/" + studio.scene.rig.cameras[1].name);
  EXPECT_EQ(camera1.clock_steps(), 3u);  // away, from +1 s to -1 s, back
  EXPECT_GE(camera1.dropped(), 110u);
  EXPECT_EQ(h.streams(0).clock_steps(), 0u);
}

// mocapd tells the path which connection each message came on: when one closes, the streams
// last heard on it (a box's camera, a hub's IMUs) are not waited for any more.
TEST(InputPath, TheStreamsOfALinkThatClosedAreNotWaitedFor) {
  const Studio studio;
  InputPath path = studio.Path();
  enum Link { kHub, kBox0, kBox1 };
  int64_t now = kT0;
  for (int k = 0; k < 3; ++k) {
    now = kT0 + k * kFrame + 5 * kMs;
    path.Feed(studio.Imus(k), now, nullptr, nullptr, kHub);
    path.Feed(studio.Keypoints(k, 0), now, nullptr, nullptr, kBox0);
    path.Feed(studio.Keypoints(k, 1), now, nullptr, nullptr, kBox1);
    ASSERT_EQ(path.TakeReady(now).size(), 1u);
  }
  now = kT0 + 3 * kFrame + 5 * kMs;
  path.Feed(studio.Imus(3), now, nullptr, nullptr, kHub);
  path.Feed(studio.Keypoints(3, 0), now, nullptr, nullptr, kBox0);
  EXPECT_TRUE(path.TakeReady(now).empty());  // box 1 is waited for
  path.LinkDown(InputPath::kNoLink);         // a recording's messages have no link: nothing
  path.LinkDown(kBox1);
  EXPECT_TRUE(path.sync().CameraActive(0, now));
  EXPECT_FALSE(path.sync().CameraActive(1, now));
  for (size_t i = 0; i < studio.scene.imus.size(); ++i)
    EXPECT_TRUE(path.sync().ImuActive(static_cast<int>(i), now));
  const std::vector<SyncedFrame> ready = path.TakeReady(now);
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_EQ(ready[0].cameras_clocked, std::vector<int>{0});
  path.LinkDown(kHub);
  for (size_t i = 0; i < studio.scene.imus.size(); ++i)
    EXPECT_FALSE(path.sync().ImuActive(static_cast<int>(i), now));
}

}  // namespace
}  // namespace mocap
