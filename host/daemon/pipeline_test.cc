// The host pipeline on messages rendered from a synthetic studio: poses follow the
// streams, bad messages are counted and dropped, stopped streams degrade and recover.
#include "pipeline.h"

#include <gtest/gtest.h>

#include <fstream>

#include "pipeline_test_messages.h"
#include "synthetic_scene.h"

namespace mocap {
namespace {

using testing::MakeScene;
using testing::Scene;

constexpr int64_t kT0 = 1'763'900'000'000'000'000;
constexpr int64_t kFrame = 16'666'667;
constexpr int64_t kMs = 1'000'000;

struct Studio {
  Scene scene = MakeScene(4);
  std::vector<Eigen::VectorXd> poses;
  Studio() {
    std::mt19937 rng(3);
    const Eigen::VectorXd a = testing::RandomPose(scene.skeleton, &rng, 0.3);
    const Eigen::VectorXd b = testing::RandomPose(scene.skeleton, &rng, 0.3);
    for (int k = 0; k < 90; ++k) poses.push_back(a + (b - a) * (k / 89.0));
  }
  std::unique_ptr<HostPipeline> Pipeline(const Scene* told = nullptr,
                                         bool imus_calibrated = true) const {
    return testing::ScenePipeline(told ? *told : scene, 1, imus_calibrated);
  }
  std::string Keypoints(int k, int c) const {
    const std::vector<Keypoint2D> person = testing::Render(scene, poses[k], 0).cameras[c].keypoints;
    std::vector<Keypoint2D> decoy = person;  // a bystander, shifted by 300 px
    for (Keypoint2D& kp : decoy) kp.x += 300, kp.confidence = 0.5;
    return testing::CameraFrame(scene, c, k, kT0 + k * kFrame, {decoy, person});
  }
  std::string Imus(int k, const std::string& skip = "") const {
    const FrameObservations obs = testing::Render(scene, poses[k], 0);
    v1::ImuBatch b;
    b.set_hub_id("hub0");
    b.set_sequence(k);
    for (const ImuObservation& o : obs.imus) {
      if (scene.imus[o.imu].name == skip) continue;
      v1::ImuSample* s = b.add_samples();
      s->set_sensor_id(scene.imus[o.imu].name);
      s->set_sample_time_ns(kT0 + k * kFrame);
      s->set_qw(o.orientation.w()), s->set_qx(o.orientation.x()), s->set_qy(o.orientation.y()),
          s->set_qz(o.orientation.z());
      s->set_status(v1::ImuSample::STATUS_ACCELERATION_INVALID);  // Render gives no accelerations
      s->set_packet_counter(k);
    }
    return b.SerializeAsString();
  }
};

TEST(Pipeline, PosesFollowTheStreamsAndBadMessagesAreCountedAndDropped) {
  Studio studio;
  auto pipeline = studio.Pipeline();
  std::vector<SolvedFrame> out;
  for (int k = 0; k < 40; ++k) {
    const int64_t now = kT0 + k * kFrame + kMs;
    EXPECT_TRUE(pipeline->Feed("mocap.v1.ImuBatch", studio.Imus(k), now));
    for (int c = 0; c < 4; ++c)
      EXPECT_TRUE(pipeline->Feed("mocap.v1.KeypointFrame", studio.Keypoints(k, c), now));
    if (k == 10) {  // garbage of every kind, between good messages
      v1::KeypointFrame nan_frame;
      nan_frame.ParseFromString(studio.Keypoints(k + 1, 0));
      nan_frame.mutable_persons(1)->set_x(3, NAN);
      EXPECT_FALSE(pipeline->Feed("mocap.v1.KeypointFrame", nan_frame.SerializeAsString(), now));
      EXPECT_FALSE(pipeline->Feed("mocap.v2.KeypointFrame", studio.Keypoints(k + 1, 0), now));
      EXPECT_FALSE(pipeline->Feed("mocap.v1.KeypointFrame", "\x12\x34garbage", now));
      v1::KeypointFrame stranger;
      stranger.ParseFromString(studio.Keypoints(k + 1, 0));
      stranger.set_camera_id("cam99");
      EXPECT_FALSE(pipeline->Feed("mocap.v1.KeypointFrame", stranger.SerializeAsString(), now));
      stranger.set_camera_id(studio.scene.rig.cameras[0].name);
      stranger.set_keypoint_layout("coco17");
      EXPECT_FALSE(pipeline->Feed("mocap.v1.KeypointFrame", stranger.SerializeAsString(), now));
      EXPECT_FALSE(
          pipeline->Feed("mocap.v1.KeypointFrame", studio.Keypoints(k - 5, 1), now));  // late
    }
    for (auto& f : pipeline->Solve(now)) out.push_back(std::move(f));
  }
  ASSERT_EQ(out.size(), 40u);
  for (size_t k = 0; k < out.size(); ++k) {
    const v1::PoseFrame& p = out[k].pose;
    EXPECT_EQ(p.capture_time_ns(), kT0 + static_cast<int64_t>(k) * kFrame);
    EXPECT_EQ(p.cameras_size(), 4);
    EXPECT_EQ(p.imus_size(), 13);
    const Eigen::VectorXd theta =
        Eigen::Map<const Eigen::VectorXd>(p.theta().data(), p.theta_size());
    if (k >= 2) EXPECT_LT(testing::MaxSiteError(studio.scene, theta, studio.poses[k]), 0.01) << k;
  }
  const auto& dropped = pipeline->dropped();
  EXPECT_EQ(dropped.at("not_finite"), 1u);
  EXPECT_EQ(dropped.at("wrong_version"), 1u);
  EXPECT_EQ(dropped.at("undecodable"), 1u);
  EXPECT_EQ(dropped.at("unknown_source"), 1u);
  EXPECT_EQ(dropped.at("invalid"), 1u);
  const v1::Health health = pipeline->Health(kT0 + 40 * kFrame);
  EXPECT_EQ(health.frames_solved(), 40u);
  EXPECT_EQ(health.streams(1).stream(), "camera/" + studio.scene.rig.cameras[1].name);
  EXPECT_EQ(health.streams(1).late(), 1u);
}

TEST(Pipeline, FlushSolvesWhatIsStillWaitingAtTheEndOfTheInput) {
  // An offline solve's last frames wait for input that never comes: a camera that stopped
  // delivering one frame early. Flush releases and solves them, once.
  Studio studio;
  auto pipeline = studio.Pipeline();
  size_t solved = 0;
  for (int k = 0; k < 10; ++k) {
    const int64_t now = kT0 + k * kFrame + kMs;
    pipeline->Feed("mocap.v1.ImuBatch", studio.Imus(k), now);
    for (int c = 0; c < (k == 9 ? 3 : 4); ++c)
      pipeline->Feed("mocap.v1.KeypointFrame", studio.Keypoints(k, c), now);
    solved += pipeline->Solve(now).size();
  }
  EXPECT_EQ(solved, 9u);
  const std::vector<SolvedFrame> last = pipeline->Flush();
  ASSERT_EQ(last.size(), 1u);
  EXPECT_EQ(last[0].pose.capture_time_ns(), kT0 + 9 * kFrame);
  EXPECT_EQ(last[0].pose.cameras_size(), 3);
  EXPECT_TRUE(pipeline->Flush().empty());
  EXPECT_EQ(pipeline->frames_solved(), 10u);
}

TEST(Pipeline, AnImuHubsOwnHealthIsFoldedIntoTheHostsAndGoesStaleWhenItStops) {
  Studio studio;
  auto pipeline = studio.Pipeline();
  v1::Health hub;
  hub.set_source("hub0");
  v1::StreamHealth* node = hub.add_streams();
  node->set_stream("imu/pelvis");
  node->set_active(true);
  node->set_lost(4);
  node->set_clock_residual_us(12.5);
  hub.add_streams()->set_stream("bus");
  EXPECT_TRUE(pipeline->Feed("mocap.v1.Health", hub.SerializeAsString(), kT0));
  v1::Health nameless = hub;
  nameless.clear_source();
  EXPECT_FALSE(pipeline->Feed("mocap.v1.Health", nameless.SerializeAsString(), kT0));
  const auto find = [](const v1::Health& h, const std::string& name) {
    for (const v1::StreamHealth& s : h.streams())
      if (s.stream() == name) return s;
    ADD_FAILURE() << "no stream " << name;
    return v1::StreamHealth();
  };
  const v1::Health now = pipeline->Health(kT0 + 1'000'000'000);
  const v1::StreamHealth pelvis = find(now, "hub0/imu/pelvis");
  EXPECT_TRUE(pelvis.active());
  EXPECT_EQ(pelvis.lost(), 4u);
  EXPECT_EQ(pelvis.clock_residual_us(), 12.5);
  EXPECT_FALSE(find(now, "hub0/bus").active());  // as the hub reported it
  EXPECT_FALSE(find(pipeline->Health(kT0 + 5'000'000'000), "hub0/imu/pelvis").active());
  EXPECT_EQ(pipeline->dropped().at("invalid"), 1u);  // the nameless one
}

TEST(Pipeline, AStoppedCameraOrImuDegradesTheSolveWhichRecoversWhenItReturns) {
  Studio studio;
  auto pipeline = studio.Pipeline();
  std::vector<SolvedFrame> out;
  const auto off = [](int k) {
    return k >= 25 && k < 60;
  };  // camera 2 and the lower-back IMU unplugged
  for (int k = 0; k < 90; ++k) {
    const int64_t now = kT0 + k * kFrame + kMs;
    pipeline->Feed("mocap.v1.ImuBatch", studio.Imus(k, off(k) ? "lower_back" : ""), now);
    for (int c = 0; c < 4; ++c) {
      if (!(c == 2 && off(k)))
        pipeline->Feed("mocap.v1.KeypointFrame", studio.Keypoints(k, c), now);
    }
    for (auto& f : pipeline->Solve(now)) out.push_back(std::move(f));
  }
  ASSERT_GE(out.size(), 89u);  // the last may wait for its deadline
  for (size_t k = 2; k < out.size(); ++k) {
    const v1::PoseFrame& p = out[k].pose;
    const Eigen::VectorXd theta =
        Eigen::Map<const Eigen::VectorXd>(p.theta().data(), p.theta_size());
    EXPECT_LT(testing::MaxSiteError(studio.scene, theta, studio.poses[k]), 0.01) << k;
    EXPECT_EQ(p.cameras_size(), off(static_cast<int>(k)) ? 3 : 4) << k;
    EXPECT_EQ(p.imus_size(), off(static_cast<int>(k)) ? 12 : 13) << k;
    // Frames wait for the stopped camera only until it is stale (300 ms), never after.
    const int64_t waited = out[k].last_input_ns - (kT0 + static_cast<int64_t>(k) * kFrame);
    if (k < 25 || k > 50) EXPECT_LE(waited, kFrame + kMs) << k;
  }
}

TEST(Pipeline, LostFramesAreCountedAcrossReorderingAndABoxRestart) {
  Studio studio;
  auto pipeline = studio.Pipeline();
  const std::string camera = studio.scene.rig.cameras[0].name;
  // Frame indices as a box sends them: in order, one late (2: not lost), a gap of 2 (4, 5),
  // then the box restarts (index back to 0, time going on) and loses one more (2).
  const std::vector<std::pair<int, int>> sent = {{0, 0}, {1, 1},  {3, 3},  {2, 2}, {6, 6},
                                                 {7, 7}, {0, 70}, {1, 71}, {3, 73}};
  for (const auto& [index, k] : sent) {
    v1::KeypointFrame f;
    f.ParseFromString(studio.Keypoints(k % 90, 0));
    f.set_frame_index(index);
    f.set_capture_time_ns(kT0 + k * kFrame);
    pipeline->Feed("mocap.v1.KeypointFrame", f.SerializeAsString(), kT0 + k * kFrame + kMs);
  }
  const v1::Health health = pipeline->Health(kT0 + 80 * kFrame);
  ASSERT_EQ(health.streams(0).stream(), "camera/" + camera);
  EXPECT_EQ(health.streams(0).lost(), 3u);  // 4 and 5 before the restart, 2 after it
}

v1::Calibration CalibrationOf(const Scene& scene, int64_t valid_from_ns) {
  v1::Calibration c;
  c.set_source("calibrator");
  c.set_valid_from_ns(valid_from_ns);
  c.set_skeleton_json(SkeletonToJson(scene.skeleton));
  c.set_imus_json(ImuSitesToJson(scene.skeleton, scene.imus));
  c.set_layout_json(KeypointLayoutToJson(scene.skeleton, scene.layout));
  return c;
}

// Calibrations that do not fit the session (a renamed bone, an unknown IMU, broken JSON, an
// empty message): each refused.
void FeedBadCalibrations(HostPipeline* pipeline, const Studio& studio, int64_t now) {
  Scene renamed = studio.scene;
  std::vector<Skeleton::Bone> bones = renamed.skeleton.bones();
  bones[4].name = "tail";
  std::string error;
  ASSERT_TRUE(Skeleton::Create(bones, &renamed.skeleton, &error)) << error;
  Scene stranger = studio.scene;
  stranger.imus[2].name = "stranger";
  for (const Scene* bad : {&renamed, &stranger}) {
    EXPECT_FALSE(
        pipeline->Feed("mocap.v1.Calibration", CalibrationOf(*bad, kT0).SerializeAsString(), now));
  }
  v1::Calibration broken = CalibrationOf(studio.scene, kT0);
  broken.set_imus_json("{\"format\": \"mocap.imus/1\", \"imus\": [");
  EXPECT_FALSE(pipeline->Feed("mocap.v1.Calibration", broken.SerializeAsString(), now));
  v1::Calibration empty;
  EXPECT_FALSE(pipeline->Feed("mocap.v1.Calibration", empty.SerializeAsString(), now));
}

Eigen::Vector3d JointOf(const v1::PoseFrame& p, const Skeleton& skeleton, const std::string& bone) {
  const v1::JointTransform& j = p.joints(skeleton.BoneIndex(bone));
  return {j.px(), j.py(), j.pz()};
}

void ExpectCalibrationStreamCounts(const v1::Health& health) {
  const auto it =
      std::find_if(health.streams().begin(), health.streams().end(),
                   [](const v1::StreamHealth& s) { return s.stream() == "calibration"; });
  ASSERT_NE(it, health.streams().end());
  EXPECT_EQ(it->received(), 2u);
  EXPECT_EQ(it->duplicates(), 1u);
  EXPECT_EQ(it->malformed(), 3u);
  EXPECT_EQ(it->dropped(), 3u);  // the rejected ones; a repeat loses nothing
  EXPECT_TRUE(it->active());
  const auto input = std::find_if(health.streams().begin(), health.streams().end(),
                                  [](const v1::StreamHealth& s) { return s.stream() == "input"; });
  ASSERT_NE(input, health.streams().end());
  EXPECT_EQ(input->malformed(), 1u);  // the empty one; the rejected calibrations are counted above
}

// A session started before its IMUs are calibrated (a skeleton 6% off, IMU mountings
// unknown): solved from video alone until a Calibration comes, then with the IMUs and the
// calibration's skeleton from the frame captured at its valid_from_ns on. Calibrations that
// do not fit the session are counted and dropped, and change nothing.
TEST(Pipeline, ACalibrationAppliesFromItsCaptureTime) {
  Studio studio;
  Scene told = studio.scene;
  std::vector<Skeleton::Bone> bones = told.skeleton.bones();
  for (Skeleton::Bone& b : bones) b.offset *= 1.06;
  std::string error;
  ASSERT_TRUE(Skeleton::Create(bones, &told.skeleton, &error)) << error;
  for (ImuSite& i : told.imus) i.mount.setIdentity(), i.reference.setIdentity();
  auto pipeline = studio.Pipeline(&told, false);
  Scene partial = studio.scene;  // the left forearm's sensor left out
  const std::string left_out = partial.imus[5].name;
  partial.imus.erase(partial.imus.begin() + 5);
  v1::Calibration second = CalibrationOf(partial, kT0 + 40 * kFrame);
  second.set_sequence(1);

  std::vector<SolvedFrame> out;
  for (int k = 0; k < 60; ++k) {
    const int64_t now = kT0 + k * kFrame + kMs;
    if (k == 5) {
      FeedBadCalibrations(pipeline.get(), studio, now);
      EXPECT_TRUE(pipeline->Feed("mocap.v1.Calibration",
                                 CalibrationOf(studio.scene, kT0 + 20 * kFrame).SerializeAsString(),
                                 now));
      EXPECT_TRUE(pipeline->Feed("mocap.v1.Calibration", second.SerializeAsString(), now));
    }
    if (k == 45)  // the calibrator repeats its latest (for late joiners): taken once only
      EXPECT_TRUE(pipeline->Feed("mocap.v1.Calibration", second.SerializeAsString(), now));
    pipeline->Feed("mocap.v1.ImuBatch", studio.Imus(k), now);
    for (int c = 0; c < 4; ++c)
      pipeline->Feed("mocap.v1.KeypointFrame", studio.Keypoints(k, c), now);
    for (auto& f : pipeline->Solve(now)) out.push_back(std::move(f));
  }
  ASSERT_EQ(out.size(), 60u);
  const Skeleton& truth = studio.scene.skeleton;
  const double shin_length = truth.bone(truth.BoneIndex("foot_l")).offset.norm();
  for (size_t k = 0; k < out.size(); ++k) {
    const v1::PoseFrame& p = out[k].pose;
    EXPECT_EQ(p.imus_size(), k < 20 ? 0 : k < 40 ? 13 : 12) << k;
    if (k >= 40) {
      for (const std::string& name : p.imus()) EXPECT_NE(name, left_out);
    }
    // From the calibration on, the bones published are the calibration's (the true ones).
    EXPECT_NEAR((JointOf(p, truth, "foot_l") - JointOf(p, truth, "shin_l")).norm(),
                k < 20 ? 1.06 * shin_length : shin_length, 1e-6)
        << k;
    const Eigen::VectorXd theta =
        Eigen::Map<const Eigen::VectorXd>(p.theta().data(), p.theta_size());
    if (k >= 20) EXPECT_LT(testing::MaxSiteError(studio.scene, theta, studio.poses[k]), 0.002) << k;
  }
  EXPECT_EQ(pipeline->calibrations_applied(), 2u);
  EXPECT_EQ(pipeline->dropped().at("invalid_calibration"), 3u);
  EXPECT_EQ(pipeline->dropped().at("invalid"), 1u);  // the empty one, by the wire check
  ExpectCalibrationStreamCounts(pipeline->Health(kT0 + 60 * kFrame));
}

TEST(Pipeline, ASessionFileThatIsWrongSaysWhat) {
  Session s;
  std::string error;
  EXPECT_FALSE(LoadSession("/nonexistent/session.json", &s, &error));
  EXPECT_NE(error.find("/nonexistent/session.json"), std::string::npos);
  const std::string path = ::testing::TempDir() + "/session.json";
  std::ofstream(path)
      << R"({"format": "mocap.session/1", "skeleton": ")"
      << testing::DataPath("skeleton_default.json")
      << R"(", "rig": "missing_rig.json", "layout": "x", "imus": "y", "inputs": [], "output": ""})";
  EXPECT_FALSE(LoadSession(path, &s, &error));
  EXPECT_NE(error.find("missing_rig.json"), std::string::npos) << error;
}

}  // namespace
}  // namespace mocap
