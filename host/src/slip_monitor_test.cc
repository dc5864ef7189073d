// Sensors that slip mid-take: detected from the keypoints, left out, trusted again.
#include "mocap/slip_monitor.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "mocap/so3.h"
#include "mocap/solver.h"
#include "synthetic_scene.h"

namespace mocap {
namespace {

constexpr double kRate = 60.0;

int ImuIndex(const testing::Scene& scene, const std::string& name) {
  for (size_t i = 0; i < scene.imus.size(); ++i) {
    if (scene.imus[i].name == name) return static_cast<int>(i);
  }
  ADD_FAILURE() << "no IMU " << name;
  return 0;
}

// A take of `seconds` at 60 fps: every joint swings slowly about a random pose, the
// keypoints carry 2 px of noise, and from slip_from to slip_until (s) one sensor's readings
// are turned on its segment by `slip` (its own frame).
struct SlipTake {
  std::string sensor;
  Eigen::Matrix3d slip = Eigen::Matrix3d::Identity();
  double slip_from = 1.0, slip_until = 1e9, seconds = 3.0;
  std::string layout = "blazepose33";
};

struct TakeOutcome {
  std::vector<double> times;
  std::vector<std::vector<int>> distrusted;  // per frame
  std::vector<double> bone_error_deg;        // of the slipped sensor's bone
};

TakeOutcome RunTake(const SlipTake& take) {
  const testing::Scene scene = testing::MakeScene(6, take.layout);
  std::mt19937 rng(21);
  const Eigen::VectorXd rest = testing::RandomPose(scene.skeleton, &rng, 0.3);
  Eigen::VectorXd swing = Eigen::VectorXd::Zero(rest.size());
  std::normal_distribution<double> normal;
  for (int i = 6; i < swing.size(); ++i) swing[i] = 0.15 * normal(rng);
  auto pose_at = [&](double t) -> Eigen::VectorXd { return rest + std::sin(2.0 * t) * swing; };
  std::vector<Eigen::VectorXd> samples;
  for (double t = 0; t < take.seconds; t += 0.25) samples.push_back(pose_at(t));
  auto solver =
      testing::MakeSolver(scene, testing::PriorThrough(samples, 40, &rng), SolverOptions());
  const int imu = ImuIndex(scene, take.sensor);
  const int bone = scene.imus[imu].bone;
  TakeOutcome out;
  for (int f = 0; f < take.seconds * kRate; ++f) {
    const double t = f / kRate;
    const Eigen::VectorXd truth = pose_at(t);
    FrameObservations obs = testing::Render(scene, truth, t);
    for (CameraObservation& c : obs.cameras) {
      for (Keypoint2D& k : c.keypoints) k.x += 2 * normal(rng), k.y += 2 * normal(rng);
    }
    if (t >= take.slip_from && t < take.slip_until) {
      Eigen::Quaterniond& q = obs.imus[imu].orientation;
      q = Eigen::Quaterniond(q.toRotationMatrix() * take.slip);
    }
    const SolveResult r = solver->Solve(obs);
    out.times.push_back(t);
    out.distrusted.push_back(r.imus_distrusted);
    BodyPose solved, real;
    ForwardKinematics(scene.skeleton, r.theta.data(), &solved);
    ForwardKinematics(scene.skeleton, truth.data(), &real);
    out.bone_error_deg.push_back(
        Log(solved.rotation[bone].transpose() * real.rotation[bone]).norm() * 180 / M_PI);
  }
  return out;
}

// First time from which `imu` is distrusted on every frame up to `until` (NaN: never).
double DistrustedFrom(const TakeOutcome& o, int imu, double until = 1e9) {
  double from = NAN;
  for (size_t f = 0; f < o.times.size() && o.times[f] < until; ++f) {
    const bool out = std::count(o.distrusted[f].begin(), o.distrusted[f].end(), imu) > 0;
    if (out && std::isnan(from)) from = o.times[f];
    if (!out) from = NAN;
  }
  return from;
}

TEST(SlipMonitor, ASlippedForearmSensorIsLeftOutWithinASecondAndItsBoneFollowsTheKeypoints) {
  SlipTake take;
  take.sensor = "forearm_l";
  take.slip = Exp(Eigen::Vector3d(0, 0, 60 * M_PI / 180));
  const TakeOutcome o = RunTake(take);
  const testing::Scene scene = testing::MakeScene(6);
  const int imu = ImuIndex(scene, "forearm_l");
  const double from = DistrustedFrom(o, imu);
  ASSERT_FALSE(std::isnan(from)) << "never distrusted";
  EXPECT_GT(from, take.slip_from);
  EXPECT_LT(from, take.slip_from + 1.0);
  for (size_t f = 0; f < o.times.size(); ++f) {
    for (int i : o.distrusted[f]) EXPECT_EQ(i, imu) << scene.imus[i].name << " at " << o.times[f];
    if (o.times[f] > from + 0.2) EXPECT_LT(o.bone_error_deg[f], 10.0) << "at " << o.times[f];
  }
}

TEST(SlipMonitor, OfASlippedShinTheShinIsLeftOutNotTheFootBelowIt) {
  SlipTake take;
  take.sensor = "shin_r";
  take.slip = Exp(Eigen::Vector3d(90 * M_PI / 180, 0, 0));
  const TakeOutcome o = RunTake(take);
  const testing::Scene scene = testing::MakeScene(6);
  EXPECT_LT(DistrustedFrom(o, ImuIndex(scene, "shin_r")), take.slip_from + 1.0);
  for (size_t f = 0; f < o.times.size(); ++f) {
    for (int i : o.distrusted[f]) EXPECT_EQ(scene.imus[i].name, "shin_r") << "at " << o.times[f];
  }
}

TEST(SlipMonitor, ASensorPutBackIsTrustedAgain) {
  SlipTake take;
  take.sensor = "forearm_r";
  take.slip = Exp(Eigen::Vector3d(50 * M_PI / 180, 0, 0));
  take.slip_until = 2.0;
  take.seconds = 4.0;
  const TakeOutcome o = RunTake(take);
  const int imu = ImuIndex(testing::MakeScene(6), "forearm_r");
  EXPECT_LT(DistrustedFrom(o, imu, 2.0), take.slip_from + 1.0);
  EXPECT_TRUE(o.distrusted.back().empty()) << "still distrusted at the end";
}

TEST(SlipMonitor, ASensorNoKeypointObservesStaysTrusted) {
  SlipTake take;  // COCO-17 has no heel or toe: nothing contradicts the foot's sensor
  take.sensor = "foot_l";
  take.slip = Exp(Eigen::Vector3d(0, 0, 60 * M_PI / 180));
  take.layout = "coco17";
  const TakeOutcome o = RunTake(take);
  for (const auto& d : o.distrusted) EXPECT_TRUE(d.empty());
}

TEST(SlipMonitor, ASensorsOwnKeypointsAreThoseItsBoneTurnsAndNoLowerSensorsBone) {
  const testing::Scene scene = testing::MakeScene(1);
  SlipMonitor monitor(scene.skeleton, scene.layout, scene.imus);
  auto names = [&](const std::string& sensor) {
    std::vector<std::string> out;
    for (int k : monitor.own_keypoints(ImuIndex(scene, sensor)))
      out.push_back(scene.layout.names[k]);
    std::sort(out.begin(), out.end());
    return out;
  };
  EXPECT_EQ(names("thigh_r"), std::vector<std::string>{"right_knee"});
  EXPECT_EQ(names("shin_r"), std::vector<std::string>{"right_ankle"});
  EXPECT_EQ(names("foot_r"), (std::vector<std::string>{"right_foot_index", "right_heel"}));
  EXPECT_EQ(names("forearm_l"),
            (std::vector<std::string>{"left_index", "left_pinky", "left_thumb", "left_wrist"}));
}

}  // namespace
}  // namespace mocap
