// The subject among the persons of a frame: the most confident until the solver tracks,
// then the one nearest the tracked pose's projection, however confident a bystander is.
#include "subject_selector.h"

#include <gtest/gtest.h>

#include "synthetic_scene.h"

namespace mocap {
namespace {

v1::KeypointPerson* AddPerson(const std::vector<Keypoint2D>& keypoints, double shift_px,
                              float confidence, v1::KeypointFrame* f) {
  v1::KeypointPerson* p = f->add_persons();
  for (const Keypoint2D& k : keypoints)
    p->add_x(k.x + shift_px), p->add_y(k.y), p->add_confidence(confidence);
  return p;
}

TEST(SubjectSelector, TheMostConfidentWithoutAPrediction) {
  const std::vector<Keypoint2D> kps(5, Keypoint2D{100, 100, 1});
  v1::KeypointFrame f;
  AddPerson(kps, 0, 0.3f, &f);
  AddPerson(kps, 50, 0.9f, &f);
  AddPerson(kps, 90, 0.6f, &f);
  EXPECT_EQ(ChooseSubject(f, {}, 0.05), 1);
  EXPECT_EQ(ChooseSubject(v1::KeypointFrame(), {}, 0.05), 0);
}

TEST(SubjectSelector, TheNearestToThePredictionOverConfidentKeypoints) {
  const std::vector<Keypoint2D> kps(5, Keypoint2D{100, 100, 1});
  v1::KeypointFrame f;
  AddPerson(kps, 40, 0.9f, &f);
  v1::KeypointPerson* near = AddPerson(kps, 2, 0.5f, &f);
  near->set_confidence(0, 0.01f), near->set_x(0, 900);  // an outlier not detected: ignored
  std::vector<Eigen::Vector2d> predicted(5, Eigen::Vector2d(100, 100));
  predicted[4] = Eigen::Vector2d(NAN, NAN);  // behind the camera: ignored
  EXPECT_EQ(ChooseSubject(f, predicted, 0.05), 1);
}

TEST(SubjectSelector, ABystanderIsNotTakenOnceTheSolverTracks) {
  const testing::Scene scene = testing::MakeScene(4);
  std::string error;
  auto solver = Solver::Create(scene.skeleton, scene.rig, scene.layout, scene.imus, std::nullopt,
                               SolverOptions(), &error);
  ASSERT_TRUE(solver) << error;
  std::mt19937 rng(5);
  const Eigen::VectorXd pose = testing::RandomPose(scene.skeleton, &rng, 0.3);
  const FrameObservations obs = testing::Render(scene, pose, 0);
  v1::KeypointFrame f;
  AddPerson(obs.cameras[0].keypoints, 300, 1.0f, &f);  // a more confident bystander
  AddPerson(obs.cameras[0].keypoints, 0, 0.5f, &f);
  EXPECT_EQ(ChooseSubject(f, scene.rig.cameras[0], *solver), 0);  // not tracking yet
  solver->Solve(obs);
  ASSERT_TRUE(solver->initialised());
  const std::vector<Eigen::Vector2d> projected = ProjectSites(*solver, scene.rig.cameras[0]);
  ASSERT_EQ(projected.size(), obs.cameras[0].keypoints.size());
  EXPECT_NEAR(projected[0].x(), obs.cameras[0].keypoints[0].x, 1.0);
  EXPECT_EQ(ChooseSubject(f, scene.rig.cameras[0], *solver), 1);
}

}  // namespace
}  // namespace mocap
