// The subject among the persons of a camera's frames: the largest to start with, then the one
// nearest the camera's previous choice (a larger bystander does not take over), forgotten
// after a detected frame with nobody but not after an undetected one, and the one nearest the
// tracked pose's projection once the solver tracks.
#include "subject_selector.h"

#include <gtest/gtest.h>

#include "synthetic_scene.h"

namespace mocap {
namespace {

constexpr double kMinConfidence = 0.05;

// A person of `size` x `size` px whose top-left keypoint is at (x, y): 5 keypoints, the
// corners and the centre.
v1::KeypointPerson Person(double x, double y, double size, float confidence = 0.9f) {
  v1::KeypointPerson p;
  for (const auto& [dx, dy] : {std::pair{0.0, 0.0}, {1.0, 0.0}, {0.0, 1.0}, {1.0, 1.0}, {.5, .5}})
    p.add_x(x + dx * size), p.add_y(y + dy * size), p.add_confidence(confidence);
  return p;
}

v1::KeypointFrame Frame(const std::vector<v1::KeypointPerson>& persons, bool detected = true) {
  v1::KeypointFrame f;
  f.set_detected(detected);
  for (const v1::KeypointPerson& p : persons) *f.add_persons() = p;
  return f;
}

TEST(SubjectSelector, TheLargestToStartWithAndOfOneSizeTheMostConfident) {
  SubjectSelector selector(3, kMinConfidence);
  EXPECT_EQ(selector.Choose(Frame({Person(0, 0, 100), Person(500, 0, 300)}), 0, nullptr), 1);
  // A keypoint not detected does not widen the box.
  v1::KeypointPerson wide = Person(0, 0, 100);
  wide.set_x(3, 2000), wide.set_confidence(3, 0.01f);
  EXPECT_EQ(selector.Choose(Frame({wide, Person(500, 0, 150)}), 1, nullptr), 1);
  // Boxes within 1%: the more confident, though a pixel smaller.
  EXPECT_EQ(
      selector.Choose(Frame({Person(0, 0, 201, 0.5f), Person(500, 0, 200, 0.8f)}), 2, nullptr), 1);
  EXPECT_EQ(selector.Choose(Frame({}), 2, nullptr), -1);
}

TEST(SubjectSelector, ABystanderIsKeptOutByTheCamerasPreviousChoice) {
  SubjectSelector selector(2, kMinConfidence);
  EXPECT_EQ(selector.Choose(Frame({Person(100, 100, 200)}), 0, nullptr), 0);
  EXPECT_EQ(selector.Choose(Frame({Person(100, 100, 200)}), 1, nullptr), 0);
  // A larger, more confident bystander walks in; the subject moves a little.
  for (int k = 0; k < 5; ++k) {
    const v1::KeypointFrame f =
        Frame({Person(400 - 40 * k, 100, 400, 1.0f), Person(105 + 5 * k, 100, 200, 0.6f)});
    EXPECT_EQ(selector.Choose(f, 0, nullptr), 1) << k;
  }
  // Camera 1's memory is its own: the same frame there after a gap starts from the largest.
  EXPECT_EQ(selector.Choose(Frame({}), 1, nullptr), -1);
  EXPECT_EQ(selector.Choose(Frame({Person(400, 100, 400), Person(105, 100, 200)}), 1, nullptr), 0);
}

TEST(SubjectSelector, ADetectedFrameWithNobodyForgetsAnUndetectedOneKeeps) {
  SubjectSelector selector(1, kMinConfidence);
  const v1::KeypointFrame both = Frame({Person(600, 100, 400), Person(100, 100, 200)});
  ASSERT_EQ(selector.Choose(Frame({Person(100, 100, 200)}), 0, nullptr), 0);
  EXPECT_EQ(selector.Choose(Frame({}, /*detected=*/false), 0, nullptr), -1);  // HS mode
  EXPECT_EQ(selector.Choose(both, 0, nullptr), 1);                            // still remembered
  EXPECT_EQ(selector.Choose(Frame({}), 0, nullptr), -1);                      // nobody: a gap
  EXPECT_EQ(selector.Choose(both, 0, nullptr), 0);                            // the largest again
}

TEST(SubjectSelector, TheNearestToThePredictionOverConfidentKeypoints) {
  SubjectSelector selector(1, kMinConfidence);
  v1::KeypointPerson near = Person(102, 100, 200, 0.5f);
  near.set_confidence(0, 0.01f), near.set_x(0, 900);  // an outlier not detected: ignored
  std::vector<Eigen::Vector2d> predicted;
  const v1::KeypointPerson at = Person(100, 100, 200);
  for (int k = 0; k < at.x_size(); ++k) predicted.emplace_back(at.x(k), at.y(k));
  predicted[4] = Eigen::Vector2d(NAN, NAN);  // behind the camera: ignored
  EXPECT_EQ(selector.Choose(Frame({Person(140, 100, 250, 0.9f), near}), 0, &predicted), 1);
  // A prediction that places nothing passes on to the previous choice.
  const std::vector<Eigen::Vector2d> nowhere(5, Eigen::Vector2d(NAN, NAN));
  EXPECT_EQ(selector.Choose(Frame({Person(600, 100, 400), near}), 0, &nowhere), 1);
}

TEST(SubjectSelector, TheProjectionWinsOnceTheSolverTracks) {
  const testing::Scene scene = testing::MakeScene(4);
  std::string error;
  auto solver = Solver::Create(scene.skeleton, scene.rig, scene.layout, scene.imus, std::nullopt,
                               SolverOptions(), &error);
  ASSERT_TRUE(solver) << error;
  std::mt19937 rng(5);
  const Eigen::VectorXd pose = testing::RandomPose(scene.skeleton, &rng, 0.3);
  const FrameObservations obs = testing::Render(scene, pose, 0);
  v1::KeypointFrame f = Frame({});
  for (const double shift : {300.0, 0.0}) {  // a bystander 300 px away, then the subject
    v1::KeypointPerson* p = f.add_persons();
    for (const Keypoint2D& k : obs.cameras[0].keypoints)
      p->add_x(k.x + shift), p->add_y(k.y), p->add_confidence(shift > 0 ? 1.0f : 0.5f);
  }
  SubjectSelector selector(4, kMinConfidence);
  EXPECT_EQ(selector.Choose(f, 0, nullptr), 0);  // of one size, the more confident bystander
  EXPECT_EQ(selector.Choose(f, 0, nullptr), 0);  // and then the one nearest it
  solver->Solve(obs);
  ASSERT_TRUE(solver->initialised());
  const std::vector<Eigen::Vector2d> projected = ProjectSites(*solver, scene.rig.cameras[0]);
  ASSERT_EQ(projected.size(), obs.cameras[0].keypoints.size());
  EXPECT_NEAR(projected[0].x(), obs.cameras[0].keypoints[0].x, 1.0);
  EXPECT_EQ(selector.Choose(f, 0, &projected), 1);  // the solver has the true pose
  EXPECT_EQ(selector.Choose(f, 0, nullptr), 1);     // and the choice is remembered
}

}  // namespace
}  // namespace mocap
