// The solver's heading tracking: IMU headings pulled to what the cameras see.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "mocap/so3.h"
#include "mocap/solver.h"
#include "synthetic_scene.h"

namespace mocap {
namespace {

constexpr double kDeg = M_PI / 180.0;
using testing::MakeSolver;

// Every IMU's reference frame is told 8 degrees off in heading (a window calibration's error,
// or magnetometer drift): tracking pulls each heading to what the cameras see, and the bones
// to the truth; readings that agree with the video leave the headings where they are.
TEST(Solver, TracksHeadingsToWhatTheCamerasSee) {
  const testing::Scene scene = testing::MakeScene(4);
  std::mt19937 rng(21);
  std::vector<Eigen::VectorXd> poses;
  for (int f = 0; f < 90; ++f) poses.push_back(testing::RandomPose(scene.skeleton, &rng, 0.5));
  const double off = 8 * kDeg;
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(off, Eigen::Vector3d::UnitZ()).matrix();
  // Mean angle (rad) between the solved and true orientations of the IMUs' bones.
  auto imu_bone_error = [&](const Eigen::VectorXd& solved, const Eigen::VectorXd& truth) {
    BodyPose a, b;
    ForwardKinematics(scene.skeleton, solved.data(), &a);
    ForwardKinematics(scene.skeleton, truth.data(), &b);
    double sum = 0;
    for (const ImuSite& s : scene.imus) {
      sum += Log(a.rotation[s.bone].transpose() * b.rotation[s.bone]).norm();
    }
    return sum / scene.imus.size();
  };
  auto run = [&](double time_constant, bool told_off) {
    std::vector<ImuSite> imus = scene.imus;
    if (told_off) {
      for (ImuSite& s : imus) s.reference = turn * s.reference;
    }
    SolverOptions options;
    options.heading_time_constant = time_constant;
    std::string error;
    auto solver = Solver::Create(scene.skeleton, scene.rig, scene.layout, imus, std::nullopt,
                                 options, &error);
    EXPECT_NE(solver, nullptr) << error;
    double late_error = 0;  // over the last 30 frames
    for (size_t f = 0; f < poses.size(); ++f) {
      solver->SetWarmStart(poses[f]);
      const SolveResult r = solver->Solve(testing::Render(scene, poses[f], f / 60.0));
      if (f + 30 >= poses.size()) late_error += imu_bone_error(r.theta, poses[f]) / 30;
    }
    return std::make_pair(solver->headings(), late_error);
  };
  const auto [tracked, tracked_error] = run(0.1, true);
  for (size_t i = 0; i < tracked.size(); ++i) {
    const std::string& name = scene.imus[i].name;
    // Without a prior, video does not see the upper back's yaw (the clavicles and the lower
    // spine take it) and sees the legs' twist weakly: those move towards the truth, slower.
    const bool seen = name.find("arm") != std::string::npos || name == "head" ||
                      name == "lower_back" || name.find("shin") != std::string::npos;
    if (seen) {
      EXPECT_NEAR(tracked[i], -off, 0.5 * kDeg) << name;
    } else {
      EXPECT_LT(tracked[i], -0.5 * kDeg) << name;
      EXPECT_GT(tracked[i], -off - 0.5 * kDeg) << name;
    }
  }
  const auto [fixed, fixed_error] = run(0.0, true);
  for (double h : fixed) EXPECT_EQ(h, 0.0);
  EXPECT_LT(tracked_error, 0.5 * fixed_error);
  const auto [agreeing, agreeing_error] = run(0.1, false);
  for (double h : agreeing) EXPECT_NEAR(h, 0.0, 0.05 * kDeg);
  EXPECT_LT(agreeing_error, 0.1 * kDeg);
}

// Headings from elsewhere, 8 degrees off what the video sees (as the detector's systematic
// offsets bias it): with a baseline the tracking leaves that alone and follows only what
// changes after it, here a 5 degree turn of every sensor's reference frame at 1.5 s.
TEST(Solver, TracksHeadingDriftFromABaseline) {
  const testing::Scene scene = testing::MakeScene(4);
  std::mt19937 rng(22);
  const Eigen::Matrix3d told_turn = Eigen::AngleAxisd(8 * kDeg, Eigen::Vector3d::UnitZ()).matrix();
  const Eigen::Matrix3d drift = Eigen::AngleAxisd(5 * kDeg, Eigen::Vector3d::UnitZ()).matrix();
  std::vector<ImuSite> told = scene.imus;
  for (ImuSite& s : told) s.reference = told_turn * s.reference;
  testing::Scene drifted = scene;  // readings in reference frames turned by the drift
  for (ImuSite& s : drifted.imus) s.reference = drift * s.reference;
  SolverOptions options;
  options.heading_time_constant = 0.1;
  options.heading_baseline_s = 1.0;
  std::string error;
  auto solver =
      Solver::Create(scene.skeleton, scene.rig, scene.layout, told, std::nullopt, options, &error);
  ASSERT_NE(solver, nullptr) << error;
  // A performer moving about one posture: how much of a heading error the solve shows
  // depends on the posture, so a baseline is only as good as the postures it saw.
  const Eigen::VectorXd posture = testing::RandomPose(scene.skeleton, &rng, 0.5);
  for (int f = 0; f < 240; ++f) {
    const Eigen::VectorXd pose = testing::Perturb(posture, 5 * kDeg, 0.02, &rng);
    solver->SetWarmStart(pose);
    solver->Solve(testing::Render(f < 90 ? scene : drifted, pose, f / 60.0));
    if (f == 50) {
      for (double h : solver->headings()) EXPECT_EQ(h, 0.0);  // learning the baseline
    }
    if (f == 89) {
      for (double h : solver->headings()) EXPECT_NEAR(h, 0.0, 1.0 * kDeg);  // the offset stays
    }
  }
  for (size_t i = 0; i < told.size(); ++i) {
    const std::string& name = told[i].name;
    const bool seen = name.find("arm") != std::string::npos || name == "head" ||
                      name == "lower_back" || name.find("shin") != std::string::npos;
    // Measured 2.7-5.1 deg for these: the baseline is a mean over the postures it saw, and
    // the yaw the solve shows is a small, posture-dependent part of the heading error when
    // the sensors win over the keypoints (E_R without a robust loss): 4.3-5.4 deg with one.
    if (seen) EXPECT_NEAR(solver->headings()[i], 5 * kDeg, 2.5 * kDeg) << name;
    EXPECT_GT(solver->headings()[i], 1 * kDeg) << name;  // not the -3 deg of no baseline
  }
}

}  // namespace
}  // namespace mocap
