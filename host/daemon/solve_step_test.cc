// The solve uses only calibrated IMUs; a calibration the solver accepts brings its IMUs in,
// one it refuses changes nothing.
#include "solve_step.h"

#include <gtest/gtest.h>

#include "synthetic_scene.h"

namespace mocap {
namespace {

struct SolveStepTest : ::testing::Test {
  testing::Scene scene = testing::MakeScene(4);
  Eigen::VectorXd pose;
  std::unique_ptr<SolveStep> step;
  void SetUp() override {
    std::mt19937 rng(2);
    pose = testing::RandomPose(scene.skeleton, &rng, 0.3);
    std::string error;
    auto solver = Solver::Create(scene.skeleton, scene.rig, scene.layout, scene.imus, std::nullopt,
                                 SolverOptions(), &error);
    ASSERT_TRUE(solver) << error;
    step = std::make_unique<SolveStep>(std::move(solver), false);
  }
  PendingCalibration Calibration(int left_out) const {
    PendingCalibration p;
    p.skeleton = scene.skeleton, p.layout = scene.layout, p.imus = scene.imus;
    p.calibrated.assign(scene.imus.size(), true);
    p.calibrated[left_out] = false;
    return p;
  }
};

TEST_F(SolveStepTest, UncalibratedImusAreLeftOutOfTheSolve) {
  FrameObservations frame = testing::Render(scene, pose, 0.0);
  ASSERT_EQ(frame.imus.size(), 13u);
  const SolveResult r = step->Solve(&frame);
  EXPECT_TRUE(frame.imus.empty());
  EXPECT_EQ(r.counts.orientations_used, 0);
  EXPECT_EQ(frame.cameras.size(), 4u);
  EXPECT_FALSE(step->any_imu_calibrated());
}

TEST_F(SolveStepTest, ACalibrationBringsItsImusIn) {
  std::string error;
  ASSERT_TRUE(step->Apply(Calibration(5), &error)) << error;
  EXPECT_TRUE(step->any_imu_calibrated());
  FrameObservations frame = testing::Render(scene, pose, 0.0);
  const SolveResult r = step->Solve(&frame);
  EXPECT_EQ(frame.imus.size(), 12u);
  EXPECT_EQ(r.counts.orientations_used, 12);
  for (const ImuObservation& i : frame.imus) EXPECT_NE(i.imu, 5);
}

TEST_F(SolveStepTest, ACalibrationTheSolverRefusesChangesNothing) {
  PendingCalibration bad = Calibration(0);
  std::vector<Skeleton::Bone> bones = bad.skeleton.bones();
  bones.pop_back();
  std::string error;
  ASSERT_TRUE(Skeleton::Create(bones, &bad.skeleton, &error)) << error;
  EXPECT_FALSE(step->Apply(bad, &error));
  EXPECT_NE(error.find("other bones"), std::string::npos) << error;
  EXPECT_FALSE(step->any_imu_calibrated());
  EXPECT_EQ(step->solver().skeleton().num_bones(), scene.skeleton.num_bones());
}

}  // namespace
}  // namespace mocap
