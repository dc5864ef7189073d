#include "mocap/solver.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <random>
#include <vector>

#include "mocap/so3.h"
#include "synthetic_scene.h"

namespace mocap {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kMaxJointError = 1e-3;       // metres
constexpr double kMaxBoneError = 0.1 * kDeg;  // radians

using testing::ExactOptions;
using testing::MakeSolver;

void ExpectFinite(const SolveResult& r) {
  EXPECT_TRUE(r.theta.allFinite());
  EXPECT_TRUE(std::isfinite(r.costs.position) && std::isfinite(r.costs.orientation));
}

// Three frames of smooth motion; frames 0 and 1 solved from the truth, frame 2 from a
// start 10 degrees away with all five terms active (a noise-free prior, PriorThrough).
TEST(Solver, RecoversRandomPosesFromTenDegreesAway) {
  const testing::Scene scene = testing::MakeScene(8);
  std::mt19937 rng(11);
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd base = testing::RandomPose(scene.skeleton, &rng);
    const Eigen::VectorXd velocity = 0.5 * (testing::RandomPose(scene.skeleton, &rng) - base);
    const double dt = 1.0 / 60.0;
    std::vector<Eigen::VectorXd> truth;
    for (int f = 0; f < 3; ++f)
      truth.push_back(base + velocity * (f * dt) + 0.3 * velocity * (f * f * dt * dt));
    auto solver = MakeSolver(scene, testing::PriorThrough(truth, 23, &rng));
    std::vector<FrameObservations> frames;
    for (int f = 0; f < 3; ++f) frames.push_back(testing::Render(scene, truth[f], f * dt));
    testing::SetAccelerations(scene, truth[0], 0, truth[1], dt, truth[2], 2 * dt,
                              solver->options().accel_at_rest, &frames[1]);
    for (int f = 0; f < 2; ++f) {
      solver->SetWarmStart(truth[f]);
      solver->Solve(frames[f]);
    }
    solver->SetWarmStart(testing::Perturb(truth[2], 10 * kDeg, 0.05, &rng));
    const SolveResult r = solver->Solve(frames[2]);
    ASSERT_EQ(r.status, SolveStatus::kOk) << r.message;
    EXPECT_EQ(r.counts.accelerations_used, 13);
    EXPECT_EQ(r.counts.orientations_used, 13);
    EXPECT_EQ(r.counts.keypoints_used + r.counts.keypoints_not_detected, 8 * 33);
    EXPECT_FALSE(r.flags & kAccelerationUnavailable);
    EXPECT_LT(testing::MaxJointError(scene.skeleton, r.theta, truth[2]), kMaxJointError)
        << "trial " << trial;
    EXPECT_LT(testing::MaxBoneAngleError(scene.skeleton, r.theta, truth[2]), kMaxBoneError)
        << "trial " << trial;
  }
}

TEST(Solver, FirstFrameNeedsNoGroundTruth) {
  const testing::Scene scene = testing::MakeScene(8);
  std::mt19937 rng(5);
  for (int trial = 0; trial < 3; ++trial) {
    const Eigen::VectorXd truth = testing::RandomPose(scene.skeleton, &rng, 0.4);
    auto solver = MakeSolver(scene, testing::PriorThrough({truth}, 23, &rng));
    const SolveResult r = solver->Solve(testing::Render(scene, truth, 0.0));
    ASSERT_EQ(r.status, SolveStatus::kInitialised) << r.message;
    EXPECT_LT(testing::MaxJointError(scene.skeleton, r.theta, truth), kMaxJointError);
    EXPECT_LT(testing::MaxBoneAngleError(scene.skeleton, r.theta, truth), kMaxBoneError);
  }
}

TEST(Solver, FirstFrameFromVideoOnlyReachesThePose) {
  const testing::Scene scene = testing::MakeScene(8);
  std::mt19937 rng(6);
  const Eigen::VectorXd truth = testing::RandomPose(scene.skeleton, &rng, 0.3);
  auto solver = MakeSolver(scene, std::nullopt);
  FrameObservations f = testing::Render(scene, truth, 0.0);
  f.imus.clear();
  const SolveResult r = solver->Solve(f);
  ASSERT_EQ(r.status, SolveStatus::kInitialised) << r.message;
  // Without IMUs or prior, what the cameras see is determined: every keypoint site.
  EXPECT_LT(testing::MaxSiteError(scene, r.theta, truth), kMaxJointError);
}

// One camera: the depth comes from the keypoints' spread against the skeleton's size.
TEST(Solver, FirstFrameFromOneCameraAndImus) {
  testing::Scene scene = testing::MakeScene(1);
  std::mt19937 rng(10);
  const Eigen::VectorXd truth = testing::RandomPose(scene.skeleton, &rng, 0.3);
  auto solver = MakeSolver(scene, testing::PriorThrough({truth}, 23, &rng));
  const SolveResult r = solver->Solve(testing::Render(scene, truth, 0.0));
  ASSERT_EQ(r.status, SolveStatus::kInitialised) << r.message;
  EXPECT_LT(testing::MaxJointError(scene.skeleton, r.theta, truth), kMaxJointError);
}

// Video only, IMU only, and a camera dropping out mid-sequence all solve through the
// same call.
TEST(Solver, AnySubsetOfSensorsPerFrame) {
  const testing::Scene scene = testing::MakeScene(4);
  std::mt19937 rng(9);
  const Eigen::VectorXd a = testing::RandomPose(scene.skeleton, &rng, 0.3);
  const Eigen::VectorXd b = testing::RandomPose(scene.skeleton, &rng, 0.3);
  // The motion runs from a to b; the prior spans it, and pins what video alone cannot see.
  auto solver = MakeSolver(scene, testing::PriorThrough({a, b}, 23, &rng));
  double t = 0.0;
  for (int f = 0; f < 30; ++f, t += 1.0 / 60.0) {
    const double s = f / 29.0;
    Eigen::VectorXd truth = a + s * (b - a);
    FrameObservations obs = testing::Render(scene, truth, t);
    if (f >= 10 && f < 15) obs.imus.clear();                            // video only
    if (f >= 15 && f < 20) obs.cameras.erase(obs.cameras.begin() + 1);  // camera 1 drops out
    if (f >= 20 && f < 23) obs.cameras.clear();                         // IMU only
    const SolveResult r = solver->Solve(obs);
    ExpectFinite(r);
    ASSERT_TRUE(r.status == SolveStatus::kOk || r.status == SolveStatus::kInitialised) << r.message;
    EXPECT_EQ(static_cast<bool>(r.flags & kPositionUnconstrained), f >= 20 && f < 23);
    const double tolerance =
        (f >= 20 && f < 23) ? 0.05 : kMaxJointError;  // IMU-only: position held
    EXPECT_LT(testing::MaxSiteError(scene, r.theta, truth), tolerance) << "frame " << f;
  }
}

TEST(Solver, PriorPullsTowardsItsMeanWhenDataIsMissing) {
  const testing::Scene scene = testing::MakeScene(8);
  std::mt19937 rng(2);
  const Eigen::VectorXd truth = testing::RandomPose(scene.skeleton, &rng, 0.3);
  const PosePrior prior = testing::RandomPrior(60, 23, truth, &rng);
  auto solver = MakeSolver(scene, prior);
  FrameObservations f = testing::Render(scene, truth, 0.0);
  // Only the torso IMUs: limbs are constrained by the prior alone (which is centred on truth).
  f.cameras.clear();
  f.imus.resize(3);
  solver->SetWarmStart(testing::Perturb(truth, 5 * kDeg, 0.0, &rng));
  const SolveResult r = solver->Solve(f);
  ASSERT_EQ(r.status, SolveStatus::kOk) << r.message;
  EXPECT_LT(testing::MaxBoneAngleError(scene.skeleton, r.theta, truth), 0.5 * kDeg);
  EXPECT_TRUE(r.flags & kPositionUnconstrained);
}

TEST(Solver, TermsCanBeSwitchedOffAndReportTheirCosts) {
  const testing::Scene scene = testing::MakeScene(4);
  std::mt19937 rng(4);
  const Eigen::VectorXd truth = testing::RandomPose(scene.skeleton, &rng, 0.3);
  const PosePrior prior = testing::RandomPrior(60, 23, Eigen::VectorXd::Zero(66), &rng);
  SolverOptions options = ExactOptions();
  options.orientation.enabled = false;
  auto solver = MakeSolver(scene, prior, options);
  solver->SetWarmStart(truth);
  const SolveResult r = solver->Solve(testing::Render(scene, truth, 0.0));
  EXPECT_EQ(r.counts.orientations_used, 0);
  EXPECT_EQ(r.costs.orientation, 0.0);
  EXPECT_GT(r.costs.pca_projection, 0.0);  // the prior's mean is not the pose
  EXPECT_GT(r.costs.pca_deviation, 0.0);
  EXPECT_GT(r.costs.position, 0.0);  // so the data gives way a little
}

// One iteration from 10 degrees away stops at the limit, flagged; the default limit is not
// reached. The timings are the solve's parts.
TEST(Solver, FlagsTheIterationLimit) {
  const testing::Scene scene = testing::MakeScene(8);
  std::mt19937 rng(12);
  const Eigen::VectorXd truth = testing::RandomPose(scene.skeleton, &rng, 0.3);
  const Eigen::VectorXd start = testing::Perturb(truth, 10 * kDeg, 0.05, &rng);
  for (int limit : {1, SolverOptions().max_iterations}) {
    SolverOptions options;
    options.max_iterations = limit;
    auto solver = MakeSolver(scene, std::nullopt, options);
    solver->SetWarmStart(start);
    const SolveResult r = solver->Solve(testing::Render(scene, truth, 0.0));
    ASSERT_EQ(r.status, SolveStatus::kOk) << r.message;
    EXPECT_EQ(bool(r.flags & kIterationLimit), limit == 1) << limit;
    EXPECT_EQ(r.iterations == limit, limit == 1);
    const SolveTimings& t = r.timings;
    EXPECT_GT(t.linear_solver, 0.0);
    EXPECT_GT(t.jacobian_evaluation, 0.0);
    EXPECT_GT(t.residual_evaluation, 0.0);
    EXPECT_GE(t.total, t.linear_solver + t.jacobian_evaluation + t.residual_evaluation);
  }
}

TEST(Solver, DegenerateInputGivesAStatusNeverANaN) {
  const testing::Scene scene = testing::MakeScene(4);
  std::mt19937 rng(8);
  const Eigen::VectorXd truth = testing::RandomPose(scene.skeleton, &rng, 0.3);
  auto solver = MakeSolver(scene, std::nullopt, SolverOptions());

  FrameObservations empty;
  SolveResult r = solver->Solve(empty);
  EXPECT_EQ(r.status, SolveStatus::kNoObservations);
  ExpectFinite(r);

  FrameObservations f = testing::Render(scene, truth, 0.0);
  for (ImuObservation& imu : f.imus) imu.has_acceleration = true;
  f.cameras[0].keypoints[0].x = NAN;           // NaN detection
  f.cameras[0].keypoints[1].confidence = 0.0;  // zero confidence
  f.cameras[0].keypoints[2].confidence = NAN;
  f.cameras[1].keypoints[3].y = 1e9;      // absurd pixel
  f.imus[0].orientation.coeffs() *= 2.0;  // non-unit quaternion
  f.imus[1].orientation.coeffs()(0) = NAN;
  f.imus[2].acceleration.x() = INFINITY;
  f.imus.push_back(f.imus[3]);  // duplicate sensor
  f.imus.back().imu = 3;
  f.cameras.push_back(f.cameras[0]);
  f.cameras.back().camera = 99;  // unknown camera
  r = solver->Solve(f);
  ASSERT_EQ(r.status, SolveStatus::kInitialised) << r.message;
  ExpectFinite(r);
  EXPECT_EQ(r.counts.keypoints_invalid, 3);
  EXPECT_GE(r.counts.keypoints_not_detected, 1);
  EXPECT_EQ(r.counts.orientations_invalid, 2);
  EXPECT_EQ(r.counts.accelerations_invalid, 3);  // one NaN, two without a usable orientation
  EXPECT_EQ(r.counts.unknown_sources, 2);
  EXPECT_LT(testing::MaxSiteError(scene, r.theta, truth), 0.01);

  // Out-of-order and NaN timestamps are rejected, the pose held.
  FrameObservations late = testing::Render(scene, truth, -1.0);
  r = solver->Solve(late);
  EXPECT_EQ(r.status, SolveStatus::kRejectedFrame);
  late.timestamp = NAN;
  EXPECT_EQ(solver->Solve(late).status, SolveStatus::kRejectedFrame);
  ExpectFinite(r);
}

TEST(Solver, CameraBehindTheSubjectIsCountedAndSkipped) {
  testing::Scene scene = testing::MakeScene(3);
  std::mt19937 rng(12);
  const Eigen::VectorXd truth = testing::RandomPose(scene.skeleton, &rng, 0.3);
  FrameObservations f = testing::Render(scene, truth, 0.0);
  // Turn camera 2 around: the subject is now behind it, but it still "reports" detections.
  Camera& cam = scene.rig.cameras[2];
  const Eigen::Vector3d center = cam.Center();
  cam.rotation = Exp(Eigen::Vector3d(0, M_PI, 0)) * cam.rotation;
  cam.translation = -cam.rotation * center;
  auto solver = MakeSolver(scene, std::nullopt);
  solver->SetWarmStart(truth);
  const SolveResult r = solver->Solve(f);
  ASSERT_EQ(r.status, SolveStatus::kOk) << r.message;
  ExpectFinite(r);
  EXPECT_EQ(r.counts.keypoints_behind_camera, 33);
  EXPECT_LT(testing::MaxSiteError(scene, r.theta, truth), kMaxJointError);
}

// E_A needs the two previous frames within max_history_gap; after a gap it waits for two
// new frames, and Reset forgets the motion entirely.
TEST(Solver, AccelerationTermFollowsTheHistory) {
  const testing::Scene scene = testing::MakeScene(2);
  std::mt19937 rng(13);
  const Eigen::VectorXd pose = testing::RandomPose(scene.skeleton, &rng, 0.2);
  auto solver = MakeSolver(scene, std::nullopt, SolverOptions());
  auto frame = [&](double t) {
    FrameObservations f = testing::Render(scene, pose, t);
    for (ImuObservation& o : f.imus) {  // at rest: the accelerometer reads gravity's reaction
      o.has_acceleration = true;
      o.acceleration =
          (scene.imus[o.imu].reference * o.orientation.toRotationMatrix()).transpose() *
          solver->options().accel_at_rest;
    }
    return solver->Solve(f);
  };
  EXPECT_EQ(frame(0.0).counts.accelerations_used, 0);
  EXPECT_EQ(frame(0.02).counts.accelerations_used, 0);
  SolveResult r = frame(0.04);
  EXPECT_EQ(r.counts.accelerations_used, 13);
  EXPECT_LT(r.costs.acceleration, 1e-6);  // at rest, the solution does not move
  r = frame(1.0);                         // a gap longer than max_history_gap
  EXPECT_EQ(r.counts.accelerations_used, 0);
  EXPECT_TRUE(r.flags & kAccelerationUnavailable);
  EXPECT_EQ(frame(1.02).counts.accelerations_used, 0);
  EXPECT_EQ(frame(1.04).counts.accelerations_used, 13);
  solver->Reset();
  r = frame(2.0);
  EXPECT_EQ(r.status, SolveStatus::kInitialised);
  EXPECT_EQ(r.counts.accelerations_used, 0);
}

// A calibration refined during capture: a solver started with a wrong skeleton (limbs 8%
// long) and wrong IMU mountings and headings tracks badly; given the right calibration
// mid-take it tracks exactly from the next frame on, without starting again.
TEST(Solver, TakesANewCalibrationBetweenFrames) {
  const testing::Scene truth = testing::MakeScene(8);
  testing::Scene told = truth;
  std::vector<Skeleton::Bone> bones = truth.skeleton.bones();
  for (Skeleton::Bone& b : bones) b.offset *= 1.08;
  std::string error;
  ASSERT_TRUE(Skeleton::Create(bones, &told.skeleton, &error)) << error;
  for (ImuSite& s : told.imus) {
    s.mount = s.mount * Exp(Eigen::Vector3d(0.2, -0.1, 0.15));
    s.reference = Exp(Eigen::Vector3d(0, 0, 0.3)) * s.reference;
  }
  SolverOptions options;
  options.motion.enabled = false;  // the IMUs measure no acceleration: E_M would smooth (mm)
  auto solver = MakeSolver(told, std::nullopt, options);
  std::mt19937 rng(5);
  const Eigen::VectorXd a = testing::RandomPose(truth.skeleton, &rng, 0.3);
  const Eigen::VectorXd b = testing::RandomPose(truth.skeleton, &rng, 0.3);
  std::vector<double> errors;
  std::vector<SolveStatus> statuses;
  for (int f = 0; f < 20; ++f) {
    if (f == 10) {
      ASSERT_TRUE(solver->SetCalibration(truth.skeleton, truth.layout, truth.imus, &error))
          << error;
      EXPECT_EQ(solver->skeleton().bone(5).offset, truth.skeleton.bone(5).offset);
    }
    const Eigen::VectorXd theta = a + (b - a) * (f / 19.0);
    const SolveResult r = solver->Solve(testing::Render(truth, theta, f / 60.0));
    errors.push_back(testing::MaxJointError(truth.skeleton, r.theta, theta));
    statuses.push_back(r.status);
  }
  // Measured: 13-16 cm before (the wrong mountings pull against the keypoints), 1e-9 m from
  // the first frame after.
  EXPECT_GT(*std::min_element(errors.begin() + 2, errors.begin() + 10), 0.01);
  EXPECT_LT(*std::max_element(errors.begin() + 11, errors.end()), 0.002);
  EXPECT_EQ(std::count(statuses.begin(), statuses.end(), SolveStatus::kInitialised), 1);
  for (double h : solver->headings()) EXPECT_EQ(h, 0.0);

  // A skeleton with other bones, or a layout of another size, is refused; nothing changes.
  std::vector<Skeleton::Bone> renamed = truth.skeleton.bones();
  renamed[3].name = "tail";
  Skeleton other;
  ASSERT_TRUE(Skeleton::Create(renamed, &other, &error)) << error;
  EXPECT_FALSE(solver->SetCalibration(other, truth.layout, truth.imus, &error));
  EXPECT_NE(error.find("tail"), std::string::npos) << error;
  KeypointLayout shorter = truth.layout;
  shorter.sites.pop_back();
  shorter.names.pop_back();
  EXPECT_FALSE(solver->SetCalibration(truth.skeleton, shorter, truth.imus, &error));
  std::vector<ImuSite> broken = truth.imus;
  broken[0].mount(0, 0) = NAN;
  EXPECT_FALSE(solver->SetCalibration(truth.skeleton, truth.layout, broken, &error));
  EXPECT_EQ(solver->layout().size(), truth.layout.size());
  EXPECT_TRUE(solver->imus()[0].mount.allFinite());
}

TEST(Solver, RejectsInconsistentConfiguration) {
  const testing::Scene scene = testing::MakeScene(2);
  std::string error;
  std::mt19937 rng(1);
  PosePrior wrong = testing::RandomPrior(30, 5, Eigen::VectorXd::Zero(66), &rng);
  EXPECT_EQ(Solver::Create(scene.skeleton, scene.rig, scene.layout, scene.imus, wrong,
                           SolverOptions(), &error),
            nullptr);
  EXPECT_NE(error.find("DOF"), std::string::npos);
  SolverOptions bad;
  bad.position.weight = -1;
  EXPECT_EQ(Solver::Create(scene.skeleton, scene.rig, scene.layout, scene.imus, std::nullopt, bad,
                           &error),
            nullptr);
  auto solver = MakeSolver(scene, std::nullopt, SolverOptions());
  EXPECT_FALSE(solver->SetOptions(bad, &error));
  EXPECT_EQ(solver->options().position.weight, SolverOptions().position.weight);
  SolverOptions negative_time;
  negative_time.heading_time_constant = -1;
  EXPECT_FALSE(solver->SetOptions(negative_time, &error));
}

// Cameras 400 times as far from the person, aimed at it with 400 times the focal length, see
// it as large as before: the pose they give, kilometres from them, is refused and the
// previous one held.
TEST(Solver, RefusesAPoseKilometresFromEveryCamera) {
  testing::Scene scene = testing::MakeScene(8);
  std::mt19937 rng(6);
  const Eigen::VectorXd truth = testing::RandomPose(scene.skeleton, &rng, 0.3);
  const Eigen::Vector3d root = truth.head<3>();
  for (Camera& c : scene.rig.cameras) {
    const Eigen::Vector3d far = root + 400.0 * (c.Center() - root);
    const Eigen::Vector3d z = (root - far).normalized();  // OpenCV: x right, y down, z forward
    const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
    c.rotation << x.transpose(), z.cross(x).transpose(), z.transpose();
    c.translation = -c.rotation * far;
    c.fx *= 400.0;
    c.fy *= 400.0;
  }
  auto solver = MakeSolver(scene, std::nullopt);
  FrameObservations f = testing::Render(scene, truth, 0.0);
  f.imus.clear();
  ASSERT_FALSE(f.cameras.empty());
  const SolveResult r = solver->Solve(f);
  EXPECT_EQ(r.status, SolveStatus::kFailed) << r.message;
  EXPECT_NE(r.message.find("m from the nearest camera (more than 100 m"), std::string::npos)
      << r.message;
  EXPECT_FALSE(solver->initialised());
  EXPECT_GT(r.theta.size(), 0);
}

}  // namespace
}  // namespace mocap
