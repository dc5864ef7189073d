// The solver across frames without keypoints: dead reckoning, re-acquisition, velocities.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "mocap/so3.h"
#include "mocap/solver.h"
#include "synthetic_scene.h"

namespace mocap {
namespace {

constexpr double kMaxJointError = 1e-3;  // metres
using testing::MakeSolver;

// HS-style input: keypoints in bursts, IMUs only in between. The pose drifts without
// keypoints; their return re-acquires it, and the jump is not taken for motion.
TEST(Solver, ReacquiresAfterFramesWithoutKeypoints) {
  const testing::Scene scene = testing::MakeScene(4);
  std::mt19937 rng(14);
  const Eigen::VectorXd pose = testing::RandomPose(scene.skeleton, &rng, 0.2);
  SolverOptions options;
  options.max_iterations = 4;  // a real-time budget
  auto solver = MakeSolver(scene, testing::PriorThrough({pose}, 23, &rng), options);
  auto frame = [&](double t, bool keypoints) {
    FrameObservations f = testing::Render(scene, pose, t);
    if (!keypoints) f.cameras.clear();
    return solver->Solve(f);
  };
  frame(0.0, true);
  frame(1 / 60.0, true);
  for (int i = 2; i < 8; ++i) frame(i / 60.0, false);
  Eigen::VectorXd drifted = solver->pose();
  drifted.head<3>() += Eigen::Vector3d(0.5, -0.3, 0.1);  // as if the IMUs had drifted 60 cm
  solver->SetWarmStart(drifted);
  SolveResult r = frame(8 / 60.0, false);
  EXPECT_TRUE(r.flags & kPositionUnconstrained);
  r = frame(9 / 60.0, true);
  EXPECT_LT(testing::MaxJointError(scene.skeleton, r.theta, pose), kMaxJointError);
  r = frame(10 / 60.0, true);
  EXPECT_LT(testing::MaxJointError(scene.skeleton, r.theta, pose), kMaxJointError);
}

// A subject gliding with true_velocity(frame) while the accelerometers read gravity's
// reaction only (so a change of velocity is unseen by them, as an integration drift),
// seen by cameras on the first `keypoint_frames` frames of every `period`. Returns the
// root position error of every frame (metres).
std::vector<double> GlideRootErrors(double velocity_gain, int period, int keypoint_frames,
                                    int frames,
                                    const std::function<Eigen::Vector3d(int)>& true_velocity) {
  const testing::Scene scene = testing::MakeScene(4);
  std::mt19937 rng(15);
  const Eigen::VectorXd rest = testing::RandomPose(scene.skeleton, &rng, 0.2);
  SolverOptions options;
  options.velocity_gain = velocity_gain;
  options.acceleration.weight = 1.0;  // 1 m/s^2: the accelerometers are trusted
  auto solver = MakeSolver(scene, testing::PriorThrough({rest}, 23, &rng), options);
  const double dt = 1 / 60.0;
  Eigen::VectorXd pose = rest;
  std::vector<double> errors;
  for (int f = 0; f < frames; ++f) {
    if (f > 0) pose.head<3>() += true_velocity(f) * dt;
    FrameObservations obs = testing::Render(scene, pose, f * dt);
    testing::SetAccelerations(scene, pose, f * dt - dt, pose, f * dt, pose, f * dt + dt,
                              options.accel_at_rest, &obs);
    if (f % period >= keypoint_frames) obs.cameras.clear();
    const SolveResult r = solver->Solve(obs);
    EXPECT_TRUE(r.status == SolveStatus::kOk || r.status == SolveStatus::kInitialised);
    if (f >= 2 && f % period >= keypoint_frames) EXPECT_GT(r.counts.accelerations_used, 0);
    errors.push_back((r.theta.head<3>() - pose.head<3>()).norm());
  }
  return errors;
}

double MaxOver(const std::vector<double>& v, int begin, int end) {
  return *std::max_element(v.begin() + begin, v.begin() + end);
}

// HS-style input: between bursts of keypoints, E_A carries the velocity the bursts showed.
TEST(Solver, DeadReckonsBetweenKeypointBursts) {
  auto steady = [](int) { return Eigen::Vector3d(1.2, 0.3, 0.0); };
  for (double gain : {1.0, 0.3}) {  // 1: the paper's second difference
    // Standing still instead would be 2.5 cm off per frame.
    EXPECT_LT(MaxOver(GlideRootErrors(gain, 8, 2, 48, steady), 8, 48), 0.003) << gain;
  }
}

// Dead reckoning drifts when the velocity changes unseen by the accelerometers; the
// keypoints' return shows the drift, which corrects the velocity: later gaps are tight.
TEST(Solver, ReacquisitionCorrectsTheVelocity) {
  auto changes = [](int f) { return Eigen::Vector3d(f < 8 ? 1.0 : 1.3, 0.0, 0.0); };
  // Keypoints on frames 0-1, 8-9, 16-17, ...; the velocity changes at frame 8.
  const std::vector<double> e = GlideRootErrors(0.3, 8, 2, 40, changes);
  const double first_gap = MaxOver(e, 10, 16), third_gap = MaxOver(e, 26, 32);
  EXPECT_GT(first_gap, 0.005);  // the gain-0.3 filter has not caught up after one burst
  EXPECT_LT(third_gap, 0.25 * first_gap);
}

// A tracked pose that has lost the keypoints is re-acquired from them and says so. Here
// trusted accelerometers miss that the subject stopped, and E_A's velocity carries the
// pose off while the keypoints fall into the Cauchy loss's tail: with the paper's exact
// prediction (the prediction shift alone keeps this pose within 0.3 mm, as it weakens a
// prediction so much stronger than the keypoints: residuals/prediction_shift.h).
TEST(Solver, ReacquiresWhenTheKeypointsAreLost) {
  const testing::Scene scene = testing::MakeScene(2);
  std::mt19937 rng(16);
  const Eigen::VectorXd rest = testing::RandomPose(scene.skeleton, &rng, 0.2);
  auto run = [&](double max_keypoint_cost, int* flagged) {
    SolverOptions options;
    options.acceleration.weight = 100.0;  // 0.1 m/s^2
    options.prediction_slack = 0.0;
    options.max_keypoint_cost = max_keypoint_cost;
    auto solver = MakeSolver(scene, testing::PriorThrough({rest}, 23, &rng), options);
    Eigen::VectorXd pose = rest;
    double worst = 0.0;
    *flagged = 0;
    for (int f = 0; f < 36; ++f) {
      if (f > 0 && f < 10) pose[0] += 2.0 / 60.0;  // 2 m/s, then a stop the IMUs miss
      FrameObservations obs = testing::Render(scene, pose, f / 60.0);
      testing::SetAccelerations(scene, pose, f / 60.0 - 1 / 60.0, pose, f / 60.0, pose,
                                f / 60.0 + 1 / 60.0, options.accel_at_rest, &obs);
      const SolveResult r = solver->Solve(obs);
      *flagged += (r.flags & kLostAndReacquired) != 0;
      if (f >= 26) worst = std::max(worst, testing::MaxJointError(scene.skeleton, r.theta, pose));
    }
    return worst;
  };
  int flagged = 0;
  const double without_check = run(1e9, &flagged);
  EXPECT_EQ(flagged, 0);
  EXPECT_GT(without_check, 0.05);  // carried off
  const double with_check = run(SolverOptions().max_keypoint_cost, &flagged);
  EXPECT_GT(flagged, 0);
  EXPECT_LT(with_check, 0.01);
}

}  // namespace
}  // namespace mocap
