// People grouped across views: three performers seen by four cameras, in an order each camera
// chose, come back as three groups of their own views; a person only one camera sees stays
// out; a view of someone else is never let into a group, and noisy detections still group.
#include "mocap/view_groups.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "synthetic_scene.h"

namespace mocap {
namespace {

using testing::MakeScene;
using testing::RandomPose;
using testing::Render;

// Each performer's views as ViewPersons (cameras that see at least 6 keypoints), with
// pixel noise; who[i]: the performer of people[i].
void Views(const testing::Scene& scene, const std::vector<Eigen::VectorXd>& poses, double noise_px,
           std::mt19937* rng, std::vector<ViewPerson>* people, std::vector<int>* who) {
  std::normal_distribution<double> noise(0.0, noise_px);
  for (size_t p = 0; p < poses.size(); ++p) {
    const FrameObservations frame = Render(scene, poses[p], 0.0);
    for (const CameraObservation& view : frame.cameras) {
      ViewPerson person{view.camera, {}};
      for (size_t k = 0; k < view.keypoints.size(); ++k) {
        const Keypoint2D& kp = view.keypoints[k];
        if (kp.confidence <= 0) continue;
        person.keypoints.push_back({view.camera,
                                    static_cast<int>(k),
                                    {kp.x + noise(*rng), kp.y + noise(*rng)},
                                    kp.confidence});
      }
      if (person.keypoints.size() >= 6)
        people->push_back(person), who->push_back(static_cast<int>(p));
    }
  }
  std::vector<int> order(people->size());  // shuffled: no camera lists people by performer
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::shuffle(order.begin(), order.end(), *rng);
  std::vector<ViewPerson> shuffled;
  std::vector<int> shuffled_who;
  for (int i : order) shuffled.push_back((*people)[i]), shuffled_who.push_back((*who)[i]);
  *people = shuffled, *who = shuffled_who;
}

std::vector<Eigen::VectorXd> Performers(const testing::Scene& scene, std::mt19937* rng) {
  std::vector<Eigen::VectorXd> poses;
  for (const Eigen::Vector2d& at :
       {Eigen::Vector2d(-1.0, 0.0), Eigen::Vector2d(0.2, 1.0), Eigen::Vector2d(0.8, -0.9)}) {
    Eigen::VectorXd theta = RandomPose(scene.skeleton, rng, 0.3);
    theta.head<2>() = at;
    poses.push_back(theta);
  }
  return poses;
}

TEST(GroupAcrossViews, EachPerformersViewsMakeOneGroupWhateverTheCamerasOrder) {
  const testing::Scene scene = MakeScene(4);
  std::mt19937 rng(3);
  for (const double noise_px : {0.0, 2.0}) {
    std::vector<ViewPerson> people;
    std::vector<int> who;
    Views(scene, Performers(scene, &rng), noise_px, &rng, &people, &who);
    const std::vector<std::vector<int>> groups = GroupAcrossViews(scene.rig, people);
    ASSERT_EQ(groups.size(), 3u) << "noise " << noise_px;
    std::vector<bool> seen(3, false);
    for (const std::vector<int>& g : groups) {
      for (int i : g) EXPECT_EQ(who[i], who[g[0]]) << "a view of another performer joined";
      EXPECT_EQ(static_cast<int>(g.size()),
                static_cast<int>(std::count(who.begin(), who.end(), who[g[0]])));
      EXPECT_FALSE(seen[who[g[0]]]);
      seen[who[g[0]]] = true;
      EXPECT_LT(GroupError(scene.rig, people, g, {}), noise_px + 1.0);
    }
  }
}

TEST(GroupAcrossViews, APersonOneCameraSeesAndViewsOfTwoPeopleMakeNoGroup) {
  const testing::Scene scene = MakeScene(4);
  std::mt19937 rng(5);
  std::vector<ViewPerson> people;
  std::vector<int> who;
  Views(scene, Performers(scene, &rng), 0.0, &rng, &people, &who);
  // Performer 0 in one camera only, performer 1 in another only: nothing to triangulate.
  std::vector<ViewPerson> two;
  for (size_t i = 0; i < people.size(); ++i) {
    if (who[i] == 0 && people[i].camera == 0) two.push_back(people[i]);
    if (who[i] == 1 && people[i].camera == 1) two.push_back(people[i]);
  }
  ASSERT_EQ(two.size(), 2u);
  EXPECT_TRUE(GroupAcrossViews(scene.rig, two).empty());
  EXPECT_GT(GroupError(scene.rig, two, {0, 1}, {}), 15.0);
  two.resize(1);
  EXPECT_TRUE(GroupAcrossViews(scene.rig, two).empty());
  // Two views from one camera are never one person.
  two.push_back(two[0]);
  EXPECT_TRUE(std::isinf(GroupError(scene.rig, two, {0, 1}, {})));
}

}  // namespace
}  // namespace mocap
