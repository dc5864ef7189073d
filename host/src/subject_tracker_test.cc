// Several people tracked: performers every camera lists in an order of its own are born as
// subjects once several views agree, keep their ids while they walk past each other, are
// retired when gone for long and found again when back soon; bad input is counted, not fatal.
#include "mocap/subject_tracker.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>

#include "synthetic_scene.h"

namespace mocap {
namespace {

using testing::MakeScene;
using testing::RandomPose;
using testing::Render;

constexpr double kDt = 1.0 / 60.0;

SubjectTracker::SolverFactory Factory(const testing::Scene& scene) {
  return [&scene] {
    std::string error;
    return Solver::Create(scene.skeleton, scene.rig, scene.layout, {}, std::nullopt,
                          SolverOptions{}, &error);
  };
}

// Every performer's views of the frame (keypoints with pixel noise), each camera's people in
// an order of its own; who[i]: the performer people[i] shows.
std::vector<CameraObservation> Views(const testing::Scene& scene,
                                     const std::vector<Eigen::VectorXd>& poses, double noise_px,
                                     std::mt19937* rng, std::vector<int>* who) {
  std::normal_distribution<double> noise(0.0, noise_px);
  std::vector<std::pair<CameraObservation, int>> views;
  for (size_t p = 0; p < poses.size(); ++p)
    for (CameraObservation view : Render(scene, poses[p], 0.0).cameras) {
      for (Keypoint2D& k : view.keypoints)
        if (k.confidence > 0) k.x += noise(*rng), k.y += noise(*rng);
      views.emplace_back(view, static_cast<int>(p));
    }
  std::shuffle(views.begin(), views.end(), *rng);
  std::vector<CameraObservation> people;
  who->clear();
  for (const auto& [view, p] : views) people.push_back(view), who->push_back(p);
  return people;
}

// Performer p at frame f: a fixed pose walking along x at `speed` m/s from `start`.
struct Walker {
  Eigen::VectorXd pose;
  Eigen::Vector2d start, velocity;
  Eigen::VectorXd At(int f) const {
    Eigen::VectorXd theta = pose;
    theta.head<2>() = start + velocity * (f * kDt);
    return theta;
  }
};

std::vector<Walker> Walkers(const testing::Scene& scene, std::mt19937* rng,
                            const std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>>& paths) {
  std::vector<Walker> out;
  for (const auto& [start, velocity] : paths)
    out.push_back({RandomPose(scene.skeleton, rng, 0.3), start, velocity});
  return out;
}

// Runs frames [0, frames) and returns, per subject id, the performers it was nearest each
// frame it was seen (its root within 0.2 m of theirs).
std::map<uint32_t, std::vector<int>> TrackFrames(const testing::Scene& scene,
                                                 SubjectTracker* tracker,
                                                 const std::vector<Walker>& walkers, int first,
                                                 int frames, std::mt19937* rng,
                                                 double noise_px = 1.0) {
  std::map<uint32_t, std::vector<int>> matches;
  for (int f = first; f < first + frames; ++f) {
    std::vector<Eigen::VectorXd> poses;
    for (const Walker& w : walkers) poses.push_back(w.At(f));
    std::vector<int> who;
    const std::vector<SubjectFrame> out =
        tracker->Track(f * kDt, Views(scene, poses, noise_px, rng, &who));
    for (const SubjectFrame& s : out) {
      if (s.cameras.empty()) continue;
      for (size_t p = 0; p < poses.size(); ++p)
        if ((s.result.theta.head<3>() - poses[p].head<3>()).norm() < 0.2)
          matches[s.id].push_back(static_cast<int>(p));
    }
  }
  return matches;
}

TEST(SubjectTracker, ThreePerformersAreBornOnceAndKeepTheirIdsAsTwoWalkPastEachOther) {
  const testing::Scene scene = MakeScene(4);
  std::mt19937 rng(11);
  // 0 and 1 walk towards each other 0.7 m apart sideways; 2 stands aside.
  const std::vector<Walker> walkers =
      Walkers(scene, &rng,
              {{{-1.2, -0.35}, {1.2, 0.0}}, {{1.2, 0.35}, {-1.2, 0.0}}, {{0.0, 1.6}, {0.0, 0.0}}});
  SubjectTracker tracker(Factory(scene), TrackerOptions{});
  const auto matches = TrackFrames(scene, &tracker, walkers, 0, 150, &rng);  // they pass at 1 s
  EXPECT_EQ(tracker.counts().births, 3u);
  EXPECT_EQ(tracker.tracked(), 3);
  EXPECT_EQ(tracker.counts().retired, 0u);
  ASSERT_EQ(matches.size(), 3u);
  std::vector<bool> taken(3, false);
  for (const auto& [id, performers] : matches) {
    // born after birth_frames, then that one performer on every frame: no identity swap
    EXPECT_GE(performers.size(), 150u - TrackerOptions{}.birth_frames) << "subject " << id;
    EXPECT_TRUE(std::all_of(performers.begin(), performers.end(),
                            [&](int p) { return p == performers[0]; }))
        << "subject " << id << " changed performer";
    EXPECT_FALSE(taken[performers[0]]);
    taken[performers[0]] = true;
  }
}

TEST(SubjectTracker, AssignsEachViewToItsPerformersSubject) {
  const testing::Scene scene = MakeScene(4);
  std::mt19937 rng(12);
  const std::vector<Walker> walkers =
      Walkers(scene, &rng, {{{-0.8, 0.0}, {0.5, 0.0}}, {{0.8, 0.2}, {-0.5, 0.0}}});
  SubjectTracker tracker(Factory(scene), TrackerOptions{});
  TrackFrames(scene, &tracker, walkers, 0, 20, &rng);
  std::vector<int> who;
  std::vector<uint32_t> assigned;
  std::vector<Eigen::VectorXd> poses{walkers[0].At(20), walkers[1].At(20)};
  const auto people = Views(scene, poses, 1.0, &rng, &who);
  tracker.Track(20 * kDt, people, &assigned);
  std::map<int, uint32_t> id_of;  // performer -> subject id: one each, the same in every view
  for (size_t i = 0; i < people.size(); ++i) {
    ASSERT_NE(assigned[i], 0u) << "view " << i << " unassigned";
    if (!id_of.count(who[i])) id_of[who[i]] = assigned[i];
    EXPECT_EQ(id_of[who[i]], assigned[i]);
  }
  EXPECT_EQ(id_of.size(), 2u);
  EXPECT_NE(id_of[0], id_of[1]);
}

TEST(SubjectTracker, APersonOnlyOneCameraSeesIsNeverBorn) {
  const testing::Scene scene = MakeScene(4);
  std::mt19937 rng(13);
  const std::vector<Walker> walkers = Walkers(scene, &rng, {{{0.0, 0.0}, {0.0, 0.0}}});
  SubjectTracker tracker(Factory(scene), TrackerOptions{});
  for (int f = 0; f < 30; ++f) {
    CameraObservation view = Render(scene, walkers[0].At(f), 0.0).cameras[2];
    tracker.Track(f * kDt, {view});
  }
  EXPECT_EQ(tracker.tracked(), 0);
  EXPECT_EQ(tracker.counts().views_unexplained, 30u);
  EXPECT_TRUE(tracker.Track(30 * kDt, {}).empty());  // a frame where nobody is seen
}

TEST(SubjectTracker, ALostSubjectIsFoundAgainNearbyButRetiredWhenGoneTooLong) {
  const testing::Scene scene = MakeScene(4);
  std::mt19937 rng(14);
  const std::vector<Walker> walkers = Walkers(scene, &rng, {{{0.0, 0.0}, {0.3, 0.0}}});
  TrackerOptions options;
  options.retire_s = 1.0;
  SubjectTracker tracker(Factory(scene), options);
  TrackFrames(scene, &tracker, walkers, 0, 20, &rng);
  ASSERT_EQ(tracker.tracked(), 1);
  // Gone for 0.5 s (held), back 15 cm further on: the same subject.
  for (int f = 20; f < 50; ++f) {
    const auto out = tracker.Track(f * kDt, {});
    ASSERT_EQ(out.size(), 1u);
    EXPECT_EQ(out[0].result.status, SolveStatus::kNoObservations);
  }
  auto matches = TrackFrames(scene, &tracker, walkers, 50, 20, &rng);
  EXPECT_EQ(tracker.counts().births, 1u);
  EXPECT_EQ(matches.count(1), 1u);
  // Gone for 1.5 s: retired; back: a new id.
  for (int f = 70; f < 160; ++f) tracker.Track(f * kDt, {});
  EXPECT_EQ(tracker.tracked(), 0);
  EXPECT_EQ(tracker.counts().retired, 1u);
  matches = TrackFrames(scene, &tracker, walkers, 160, 20, &rng);
  EXPECT_EQ(matches.count(2), 1u);
  EXPECT_EQ(tracker.counts().births, 2u);
}

TEST(SubjectTracker, ViewsAreNamedByTheirSubjectWhileAnotherIsRetired) {
  const testing::Scene scene = MakeScene(4);
  std::mt19937 rng(16);
  const std::vector<Walker> walkers =
      Walkers(scene, &rng, {{{-0.8, 0.0}, {0.0, 0.0}}, {{0.8, 0.0}, {0.0, 0.0}}});
  TrackerOptions options;
  options.retire_s = 0.5;
  SubjectTracker tracker(Factory(scene), options);
  TrackFrames(scene, &tracker, {walkers[0]}, 0, 10, &rng);  // walker 0: subject 1
  TrackFrames(scene, &tracker, walkers, 10, 30, &rng);      // walker 1: subject 2
  ASSERT_EQ(tracker.tracked(), 2);
  for (int f = 30; f < 80; ++f) {  // walker 0 gone: retired 0.5 s on, walker 1 still seen
    std::vector<int> who;
    std::vector<uint32_t> assigned;
    const auto people = Views(scene, {walkers[1].At(f)}, 1.0, &rng, &who);
    tracker.Track(f * kDt, people, &assigned);
    for (uint32_t a : assigned) EXPECT_EQ(a, 2u) << "frame " << f;
  }
  EXPECT_EQ(tracker.counts().retired, 1u);
  EXPECT_EQ(tracker.tracked(), 1);
}

TEST(SubjectTracker, BadViewsAreCountedAndDroppedAndACrowdIsCapped) {
  const testing::Scene scene = MakeScene(4);
  std::mt19937 rng(15);
  const std::vector<Walker> walkers = Walkers(scene, &rng, {{{0.0, 0.0}, {0.0, 0.0}}});
  TrackerOptions options;
  options.max_people_per_camera = 3;
  SubjectTracker tracker(Factory(scene), options);
  for (int f = 0; f < 10; ++f) {
    std::vector<CameraObservation> people = Render(scene, walkers[0].At(f), 0.0).cameras;
    CameraObservation crowd = people[0];  // 20 copies in camera 0: 3 kept
    for (int i = 0; i < 20; ++i) people.push_back(crowd);
    CameraObservation unknown = people[1];
    unknown.camera = 9;  // no such camera
    CameraObservation short_one = people[2];
    short_one.keypoints.resize(5);  // not the layout's count
    CameraObservation nans = people[3];
    for (Keypoint2D& k : nans.keypoints) k.x = NAN;
    people.insert(people.end(), {unknown, short_one, nans});
    tracker.Track(f * kDt, people);
  }
  // per frame: camera 0's 21 people less 3, and the three bad views
  EXPECT_EQ(tracker.counts().people_dropped, 10u * (18 + 3));
  EXPECT_EQ(tracker.tracked(), 1);
  options.gate = -1;
  EXPECT_THROW(SubjectTracker(Factory(scene), options), std::invalid_argument);
}

TEST(SubjectTracker, APersonBeyondTheCapOfSubjectsIsRefusedAndCountedOnce) {
  const testing::Scene scene = MakeScene(4);
  std::mt19937 rng(16);
  const std::vector<Walker> walkers =
      Walkers(scene, &rng, {{{-0.8, 0.0}, {0.0, 0.0}}, {{0.8, 0.0}, {0.0, 0.0}}});
  TrackerOptions options;
  options.max_subjects = 1;
  SubjectTracker tracker(Factory(scene), options);
  TrackFrames(scene, &tracker, walkers, 0, 40, &rng);  // the second asks for a birth every frame
  EXPECT_EQ(tracker.tracked(), 1);
  EXPECT_EQ(tracker.counts().births, 1u);
  EXPECT_EQ(tracker.counts().births_refused, 1u);
}

TEST(SubjectTracker, SuitsThatDoNotFitOrReadingsOfTooFewSuitsAreRefused) {
  const testing::Scene scene = MakeScene(4);
  SuitCalibration suit{scene.skeleton, scene.layout, scene.imus};
  SubjectTracker tracker(Factory(scene), TrackerOptions{}, {suit, suit});
  EXPECT_EQ(tracker.wearers(), (std::vector<uint32_t>{0, 0}));
  EXPECT_THROW(tracker.Track(0.0, {}, nullptr, {{}}), std::invalid_argument);  // one of two
  EXPECT_NO_THROW(tracker.Track(0.0, {}, nullptr, {{}, {}}));                  // none read
  SuitCalibration misfit = suit;
  misfit.imus[0].bone = 99;  // no such bone
  EXPECT_THROW(SubjectTracker(Factory(scene), TrackerOptions{}, {misfit}), std::invalid_argument);
}

}  // namespace
}  // namespace mocap
