// The host pipeline in a session of several people: every camera sends every person it sees,
// in an order of its own; the host publishes one PoseFrame per person and frame, each person
// keeping its subject id, and Health counts the people tracked. A session of one ignores the
// same bystander.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>

#include "pipeline.h"
#include "pipeline_test_messages.h"
#include "synthetic_scene.h"

namespace mocap {
namespace {

using testing::MakeScene;
using testing::Scene;

constexpr int64_t kT0 = 1'763'900'000'000'000'000;
constexpr int64_t kFrame = 16'666'667;

struct Stage {
  Scene scene = MakeScene(4);
  std::vector<Eigen::VectorXd> people;  // two performers standing 1.6 m apart
  Stage() {
    std::mt19937 rng(8);
    for (const double x : {-0.8, 0.8}) {
      Eigen::VectorXd theta = testing::RandomPose(scene.skeleton, &rng, 0.3);
      theta[0] = x, theta[1] = 0.0;
      people.push_back(theta);
    }
  }
  std::unique_ptr<HostPipeline> Pipeline(int people_in_session) const {
    return testing::ScenePipeline(scene, people_in_session);
  }
  // Camera c's frame k: both performers, walking along y, in an order that changes each frame.
  std::string Keypoints(int k, int c) const {
    std::vector<std::vector<Keypoint2D>> persons;
    for (int i = 0; i < 2; ++i)
      persons.push_back(testing::Render(scene, At((i + k + c) % 2, k), 0).cameras[c].keypoints);
    return testing::CameraFrame(scene, c, k, kT0 + k * kFrame, persons);
  }
  Eigen::VectorXd At(int p, int k) const {
    Eigen::VectorXd theta = people[p];
    theta[1] += (p == 0 ? 0.01 : -0.01) * k;  // 0.6 m/s, in opposite directions
    return theta;
  }
};

TEST(PipelinePeople, EachPersonIsPublishedWithAnIdItKeeps) {
  Stage stage;
  auto pipeline = stage.Pipeline(3);
  std::map<uint32_t, std::vector<int>> performer_of;  // subject id -> the performer, per frame
  for (int k = 0; k < 40; ++k) {
    const int64_t t = kT0 + k * kFrame;
    for (int c = 0; c < 4; ++c)
      ASSERT_TRUE(pipeline->Feed("mocap.v1.KeypointFrame", stage.Keypoints(k, c), t + 5'000'000));
    for (const SolvedFrame& f : pipeline->Solve(t + 5'000'000)) {
      ASSERT_NE(f.pose.subject_id(), 0u);
      EXPECT_EQ(f.pose.cameras_size(), 4);
      const Eigen::Vector3d root(f.pose.joints(0).px(), f.pose.joints(0).py(),
                                 f.pose.joints(0).pz());
      const int frame = static_cast<int>(f.pose.frame_index());
      for (int p = 0; p < 2; ++p)
        if ((root - stage.At(p, frame).head<3>()).norm() < 0.05)
          performer_of[f.pose.subject_id()].push_back(p);
    }
  }
  // born after 5 frames, then each frame: one id per performer, never changing hands
  ASSERT_EQ(performer_of.size(), 2u);
  for (const auto& [id, performers] : performer_of) {
    EXPECT_GE(performers.size(), 34u) << id;
    EXPECT_TRUE(std::all_of(performers.begin(), performers.end(),
                            [&](int p) { return p == performers[0]; }));
  }
  EXPECT_NE(performer_of.begin()->second[0], performer_of.rbegin()->second[0]);
  const v1::Health health = pipeline->Health(kT0 + 40 * kFrame);
  EXPECT_EQ(health.people().tracked(), 2u);
  EXPECT_EQ(health.people().born(), 2u);
  EXPECT_EQ(health.people().retired(), 0u);
}

TEST(PipelinePeople, ASessionOfOneSolvesOneSubjectWithoutAnId) {
  Stage stage;
  auto pipeline = stage.Pipeline(1);
  int published = 0;
  for (int k = 0; k < 10; ++k) {
    const int64_t t = kT0 + k * kFrame;
    for (int c = 0; c < 4; ++c)
      pipeline->Feed("mocap.v1.KeypointFrame", stage.Keypoints(k, c), t + 5'000'000);
    for (const SolvedFrame& f : pipeline->Solve(t + 5'000'000)) {
      EXPECT_EQ(f.pose.subject_id(), 0u);
      published++;
    }
  }
  for (const SolvedFrame& f : pipeline->Flush()) {
    EXPECT_EQ(f.pose.subject_id(), 0u);
    published++;
  }
  EXPECT_EQ(published, 10);
  EXPECT_FALSE(pipeline->Health(kT0 + 10 * kFrame).has_people());
}

}  // namespace
}  // namespace mocap
