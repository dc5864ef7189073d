// The solve with one camera and with the floor: the ground contact E_G, the prediction shift
// (residuals/prediction_shift.h) and the re-initialisation of a pose the keypoints cannot
// reach (solver_passes.cc).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "mocap/ground.h"
#include "mocap/so3.h"
#include "mocap/solver.h"
#include "synthetic_scene.h"

namespace mocap {
namespace {

constexpr double kRate = 60.0;
using PoseAt = std::function<Eigen::VectorXd(double)>;

// A walk-like motion: every joint swings about a random pose, the lowest foot contact on the
// floor at z = 0 at rest, the body walking along x (towards the first camera) at 1 m/s.
PoseAt Walking(const Skeleton& skeleton, std::mt19937* rng) {
  Eigen::VectorXd rest = testing::RandomPose(skeleton, rng, 0.15);
  rest.segment<3>(3) = Eigen::Vector3d(0, 0, 0.3);
  Eigen::VectorXd swing = Eigen::VectorXd::Zero(rest.size());
  std::normal_distribution<double> normal;
  for (int i = 6; i < swing.size(); ++i) swing[i] = 0.1 * normal(*rng);
  BodyPose pose;
  ForwardKinematics(skeleton, rest.data(), &pose);
  const std::vector<Site> feet = FootContactSites(skeleton);
  rest[2] -=
      (pose.position[feet[LowestSite(pose, feet)].bone] +
       pose.rotation[feet[LowestSite(pose, feet)].bone] * feet[LowestSite(pose, feet)].offset)
          .z();
  return [rest, swing](double t) -> Eigen::VectorXd {
    Eigen::VectorXd theta = rest + std::sin(5.0 * t) * swing;
    theta[0] += 1.0 * t - 1.0;
    return theta;
  };
}

// pose_at lifted or lowered each instant so that its lowest foot contact site is on z = 0.
PoseAt OnTheFloor(const Skeleton& skeleton, const PoseAt& pose_at) {
  const std::vector<Site> feet = FootContactSites(skeleton);
  return [&skeleton, feet, pose_at](double t) -> Eigen::VectorXd {
    Eigen::VectorXd theta = pose_at(t);
    BodyPose pose;
    ForwardKinematics(skeleton, theta.data(), &pose);
    const Site& c = feet[LowestSite(pose, feet)];
    theta[2] -= (pose.position[c.bone] + pose.rotation[c.bone] * c.offset).z();
    return theta;
  };
}

struct Track {
  std::vector<SolveResult> results;
  std::vector<Eigen::VectorXd> truth;
  double MaxRootError(size_t from = 0) const {
    double worst = 0;
    for (size_t f = from; f < results.size(); ++f)
      worst = std::max(worst, (results[f].theta.head<3>() - truth[f].head<3>()).norm());
    return worst;
  }
};

// `frames` frames of pose_at seen by the scene's cameras (keypoints with `pixel_noise` px of
// noise) and its 13 IMUs (accelerations of the true motion); before frame f, edit(f, solver,
// observations) may change either.
Track Solve(const testing::Scene& scene, const PoseAt& pose_at, int frames, double pixel_noise,
            const SolverOptions& options,
            const std::function<void(int, Solver*, FrameObservations*)>& edit = {}) {
  std::mt19937 rng(11);
  std::vector<Eigen::VectorXd> samples;
  for (int f = 0; f < frames; f += 20) samples.push_back(pose_at(f / kRate));
  auto solver = testing::MakeSolver(scene, testing::PriorThrough(samples, 40, &rng), options);
  std::normal_distribution<double> normal;
  Track run;
  const double dt = 1 / kRate;
  for (int f = 0; f < frames; ++f) {
    const double t = f * dt;
    FrameObservations obs = testing::Render(scene, pose_at(t), t);
    testing::SetAccelerations(scene, pose_at(t - dt), t - dt, pose_at(t), t, pose_at(t + dt),
                              t + dt, options.accel_at_rest, &obs);
    for (CameraObservation& c : obs.cameras) {
      for (Keypoint2D& k : c.keypoints)
        k.x += pixel_noise * normal(rng), k.y += pixel_noise * normal(rng);
    }
    if (edit) edit(f, solver.get(), &obs);
    run.results.push_back(solver->Solve(obs));
    run.truth.push_back(pose_at(t));
  }
  return run;
}

double FloorOf(const Skeleton& skeleton, const PoseAt& pose_at, int frames) {
  std::vector<Eigen::VectorXd> poses;
  for (int f = 0; f < frames; ++f) poses.push_back(pose_at(f / kRate));
  return FloorHeight(skeleton, poses);
}

// One camera and 13 IMUs, walking towards the camera: the paper's prediction (E_A's second
// difference from an exact previous solution) outweighs the keypoints along the camera's rays,
// and a velocity picked up there carries the body off; shifted, the prediction follows them.
TEST(OneCamera, TheBodyStaysOnItsKeypointsAlongTheCamerasRays) {
  const testing::Scene scene = testing::MakeScene(1);
  std::mt19937 rng(21);
  const PoseAt walk = Walking(scene.skeleton, &rng);
  const int frames = 300;  // 5 s
  SolverOptions paper;
  paper.prediction_slack = 0.0;
  SolverOptions ours;
  ours.floor_height = FloorOf(scene.skeleton, walk, frames);
  // Measured: 57 cm against 4.5 cm (1.9 cm after the first second).
  EXPECT_GT(Solve(scene, walk, frames, 1.0, paper).MaxRootError(), 0.3);
  const Track track = Solve(scene, walk, frames, 1.0, ours);
  EXPECT_LT(track.MaxRootError(), 0.07);
  EXPECT_LT(track.MaxRootError(60), 0.03);
  for (const SolveResult& r : track.results) EXPECT_EQ(r.flags & kReinitialised, 0u);
}

// A jump seen by 8 cameras: E_G's robust pull on feet 30 cm up does not bring them down.
TEST(Ground, AJumpIsNotPulledDown) {
  const testing::Scene scene = testing::MakeScene(8);
  std::mt19937 rng(22);
  const PoseAt stand = Walking(scene.skeleton, &rng);
  const double take_off = 0.5, flight = 0.5;  // s; 31 cm up at the top
  auto jump = [&](double t) {
    Eigen::VectorXd theta = stand(std::min(t, 0.2));
    const double s = t - take_off;
    if (s > 0.0 && s < flight) theta[2] += 0.5 * 9.81 * s * (flight - s);
    return theta;
  };
  SolverOptions with;
  with.floor_height = FloorOf(scene.skeleton, jump, 30);  // standing before the jump
  SolverOptions without;
  const int frames = 75;
  const Track a = Solve(scene, jump, frames, 2.0, with),
              b = Solve(scene, jump, frames, 2.0, without);
  const int top = static_cast<int>((take_off + flight / 2) * kRate);
  EXPECT_GT(a.results[top].costs.ground, 0.0);
  for (int f = static_cast<int>(take_off * kRate); f < frames; ++f) {
    const double lower = b.results[f].theta[2] - a.results[f].theta[2];
    EXPECT_LT(lower, 0.001) << "frame " << f;  // measured: 0.02 mm (a quadratic loss: 2.9 mm)
    EXPECT_LT(std::abs(a.results[f].theta[2] - a.truth[f][2]), 0.01) << "frame " << f;
  }
}

// The cameras lost after 1 s and every accelerometer reading 0.3 m/s^2 too far up (a bias the
// dead reckoning integrates): E_G, its loss widened where no keypoint holds the root, keeps
// the body near the floor, which with its usual loss it gives up (measured: 11 cm against 1.25 m).
TEST(Ground, WithoutCamerasTheFloorHoldsTheHeight) {
  const testing::Scene scene = testing::MakeScene(8);
  std::mt19937 rng(25);
  const PoseAt walk = OnTheFloor(scene.skeleton, Walking(scene.skeleton, &rng));
  const int frames = 240, lost = 60;  // 4 s, the last 3 without cameras
  auto dark = [&](int f, Solver*, FrameObservations* obs) {
    if (f < lost) return;
    obs->cameras.clear();
    for (ImuObservation& imu : obs->imus)
      imu.acceleration += imu.orientation.inverse() * Eigen::Vector3d(0, 0, 0.3);
  };
  SolverOptions stronger;
  stronger.floor_height = FloorOf(scene.skeleton, walk, frames);
  SolverOptions usual = stronger;
  usual.ground_unobserved_scale = 1.0;
  const Track a = Solve(scene, walk, frames, 1.0, stronger, dark),
              b = Solve(scene, walk, frames, 1.0, usual, dark);
  double rise_a = 0, rise_b = 0;
  for (int f = lost; f < frames; ++f) {
    rise_a = std::max(rise_a, std::abs(a.results[f].theta[2] - a.truth[f][2]));
    rise_b = std::max(rise_b, std::abs(b.results[f].theta[2] - b.truth[f][2]));
    EXPECT_TRUE(a.results[f].flags & kPositionUnconstrained) << "frame " << f;
  }
  EXPECT_LT(rise_a, 0.15);
  EXPECT_GT(rise_b, 0.6);
}

// Without a floor E_G is off: the same solve as with the term disabled, whatever the floor.
TEST(Ground, NoFloorSolvesAsWithoutTheTerm) {
  const testing::Scene scene = testing::MakeScene(2);
  std::mt19937 rng(23);
  const PoseAt walk = Walking(scene.skeleton, &rng);
  SolverOptions unknown;  // floor_height NaN
  SolverOptions disabled;
  disabled.floor_height = 0.0;
  disabled.ground.enabled = false;
  const Track a = Solve(scene, walk, 40, 2.0, unknown), b = Solve(scene, walk, 40, 2.0, disabled);
  for (size_t f = 0; f < a.results.size(); ++f) {
    EXPECT_EQ(a.results[f].theta, b.results[f].theta) << "frame " << f;
    EXPECT_EQ(a.results[f].costs.ground, 0.0);
  }
}

// A pose that ran through the camera along its rays (every keypoint behind it) is not held:
// the frame is solved again from its own observations, and says so.
TEST(OneCamera, APoseBehindTheCameraIsReinitialised) {
  const testing::Scene scene = testing::MakeScene(1);
  std::mt19937 rng(24);
  const PoseAt walk = Walking(scene.skeleton, &rng);
  SolverOptions options;
  options.floor_height = FloorOf(scene.skeleton, walk, 120);
  // No motion terms: they would pull the pose back to their prediction (as E_A does here); in
  // the take this was seen in (one camera, --omit A) they had followed it away.
  options.acceleration.enabled = options.motion.enabled = false;
  const Eigen::Vector3d camera = scene.rig.cameras[0].Center();
  const int jump = 30;
  const Track track =
      Solve(scene, walk, 60, 1.0, options, [&](int f, Solver* s, FrameObservations*) {
        if (f != jump) return;
        Eigen::VectorXd away = s->pose();
        away.head<3>() = camera + 150.0 * (camera - away.head<3>()).normalized();
        s->SetWarmStart(away);
      });
  const SolveResult& r = track.results[jump];
  EXPECT_TRUE(r.flags & kReinitialised);
  EXPECT_EQ(r.status, SolveStatus::kOk);
  EXPECT_GT(r.counts.keypoints_used, 20);
  EXPECT_LT((r.theta.head<3>() - track.truth[jump].head<3>()).norm(), 0.15);  // one view's depth
  EXPECT_LT(track.MaxRootError(jump + 20), 0.05);
  int reinitialised = 0;
  for (const SolveResult& x : track.results) reinitialised += (x.flags & kReinitialised) != 0;
  EXPECT_EQ(reinitialised, 1);
}

// One frame whose keypoints a detector swapped left for right in the only view: its keypoints
// sit in the loss's tail, and a re-acquisition fitting them would move the body along the
// camera's rays. It is taken only when it halves their cost: the tracked pose is kept.
TEST(OneCamera, OneFrameOfSwappedKeypointsDoesNotMoveTheBody) {
  const testing::Scene scene = testing::MakeScene(1);
  std::mt19937 rng(25);
  const PoseAt walk = OnTheFloor(scene.skeleton, Walking(scene.skeleton, &rng));
  std::vector<int> twin(scene.layout.size());
  for (int k = 0; k < scene.layout.size(); ++k) {
    std::string name = scene.layout.names[k];
    for (const auto& [a, b] :
         {std::pair<std::string, std::string>{"left", "right"}, {"right", "left"}}) {
      if (const size_t at = scene.layout.names[k].find(a); at != std::string::npos) {
        name = scene.layout.names[k];
        name.replace(at, a.size(), b);
      }
    }
    twin[k] =
        static_cast<int>(std::find(scene.layout.names.begin(), scene.layout.names.end(), name) -
                         scene.layout.names.begin());
  }
  SolverOptions options;
  options.floor_height = FloorOf(scene.skeleton, walk, 120);
  const int swapped = 40;
  const Track track =
      Solve(scene, walk, 60, 1.0, options, [&](int f, Solver*, FrameObservations* o) {
        if (f != swapped) return;
        std::vector<Keypoint2D> k = o->cameras[0].keypoints;
        for (size_t i = 0; i < k.size(); ++i) o->cameras[0].keypoints[i] = k[twin[i]];
      });
  EXPECT_GT(track.results[swapped].costs.position,
            SolverOptions().max_keypoint_cost * track.results[swapped].counts.keypoints_used);
  EXPECT_LT(track.MaxRootError(20), 0.05);
}

}  // namespace
}  // namespace mocap
