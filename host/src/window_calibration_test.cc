// The window calibration on exact observations of random poses: the bone lengths, the IMU
// headings and the directions video observes of each mounting come back from wrong starts;
// the directions it does not observe (a bone's twist about its own axis when the joint below
// is free) are not asserted. Inconsistent inputs are refused with a message.
#include "mocap/window_calibration.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>

#include "mocap/kinematics.h"
#include "mocap/so3.h"
#include "synthetic_scene.h"

namespace mocap {
namespace {

constexpr double kDeg = M_PI / 180.0;

class WindowCalibrationTest : public ::testing::Test {
 protected:
  void SetUp() override {
    told_ = testing::MakeScene(8);
    // The true body: legs 6% longer, arms 5% shorter than the skeleton the calibration starts from.
    truth_ = told_;
    group_.assign(told_.skeleton.num_bones(), -1);
    std::vector<Skeleton::Bone> bones = told_.skeleton.bones();
    const std::vector<std::pair<std::string, double>> scaled = {
        {"shin_l", 1.06},    {"shin_r", 1.06},    {"foot_l", 1.06}, {"foot_r", 1.06},
        {"forearm_l", 0.95}, {"forearm_r", 0.95}, {"hand_l", 0.95}, {"hand_r", 0.95}};
    for (const auto& [name, s] : scaled) {
      const int b = told_.skeleton.BoneIndex(name);
      bones[b].offset *= s;
      group_[b] = s > 1.0 ? 0 : 1;
    }
    std::string error;
    ASSERT_TRUE(Skeleton::Create(bones, &truth_.skeleton, &error)) << error;
    for (int t = 0; t < 30; ++t) {
      thetas_.push_back(testing::RandomPose(truth_.skeleton, &rng_));
      frames_.push_back(testing::Render(truth_, thetas_.back(), 0.1 * t));
      starts_.push_back(testing::Perturb(thetas_.back(), 0.1, 0.03, &rng_));
    }
    // Mountings 10 degrees off, headings 20 degrees off.
    for (ImuSite& s : told_.imus) {
      Eigen::Vector3d axis = Eigen::Vector3d::Random().normalized();
      s.mount = s.mount * Exp(10 * kDeg * axis);
      s.reference = Exp(Eigen::Vector3d(0, 0, 20 * kDeg)) * s.reference;
    }
    options_.scale_group = group_;
    options_.estimate_sites = false;
    options_.max_iterations = 100;
    options_.scale_sigma = 1e3;  // exact data: the prior on the lengths should not pull
  }

  std::mt19937 rng_{7};
  testing::Scene told_, truth_;
  std::vector<int> group_;
  std::vector<Eigen::VectorXd> thetas_, starts_;
  std::vector<FrameObservations> frames_;
  CalibrationOptions options_;
};

// The bone's axis (towards its first child) in the sensor frame: what video observes of M.
Eigen::Vector3d AxisInSensor(const Skeleton& s, const ImuSite& imu) {
  for (int c = 0; c < s.num_bones(); ++c) {
    if (s.bone(c).parent == imu.bone) return imu.mount.transpose() * s.bone(c).offset.normalized();
  }
  return imu.mount.transpose() * Eigen::Vector3d::UnitZ();
}

TEST_F(WindowCalibrationTest, RecoversLengthsHeadingsAndObservedMountings) {
  CalibrationResult r;
  std::string error;
  ASSERT_TRUE(CalibrateWindow(told_.skeleton, told_.rig, told_.layout, told_.imus, std::nullopt,
                              frames_, starts_, options_, &r, &error))
      << error;
  EXPECT_LT(r.final_cost, 1e-6 * r.initial_cost) << r.message;
  ASSERT_EQ(r.scales.size(), 2u);
  EXPECT_NEAR(r.scales[0], 1.06, 1e-4);
  EXPECT_NEAR(r.scales[1], 0.95, 1e-4);
  for (int b = 0; b < truth_.skeleton.num_bones(); ++b)
    EXPECT_LT((r.skeleton.bone(b).offset - truth_.skeleton.bone(b).offset).norm(), 1e-4);
  for (size_t i = 0; i < truth_.imus.size(); ++i) {
    const ImuSite &got = r.imus[i], &want = truth_.imus[i];
    EXPECT_LT(AngleBetween(got.reference, want.reference), 0.05 * kDeg) << want.name;
    const double axis_angle = std::acos(
        std::min(1.0, AxisInSensor(truth_.skeleton, got).dot(AxisInSensor(truth_.skeleton, want))));
    EXPECT_LT(axis_angle, 0.05 * kDeg) << want.name;
    EXPECT_LT(r.imu_residual_deg[i], 0.01) << want.name;
  }
  // The head is seen whole (eleven keypoints around it): its mounting comes back entirely.
  const int head = truth_.skeleton.BoneIndex("head");
  for (size_t i = 0; i < truth_.imus.size(); ++i) {
    if (truth_.imus[i].bone == head)
      EXPECT_LT(AngleBetween(r.imus[i].mount, truth_.imus[i].mount), 0.05 * kDeg);
  }
  for (size_t t = 0; t < thetas_.size(); ++t)
    EXPECT_LT(testing::MaxSiteError(truth_, r.thetas[t], thetas_[t]), 1e-4);
}

TEST_F(WindowCalibrationTest, AKneeHingePinsTheLegMountingsTwist) {
  // Knees that turn about their y axis only (as the clips' skeletons' do): with the hinge as
  // a joint convention, the thigh and shin mountings come back whole, twist included; without
  // it the twist about the bone's axis is left where it started.
  const int knees[2] = {truth_.skeleton.BoneIndex("shin_l"), truth_.skeleton.BoneIndex("shin_r")};
  for (size_t t = 0; t < thetas_.size(); ++t) {
    for (int knee : knees) {
      thetas_[t](3 + 3 * knee) = 0.0;
      thetas_[t](5 + 3 * knee) = 0.0;
    }
    frames_[t] = testing::Render(truth_, thetas_[t], 0.1 * t);
  }
  auto leg_mount_error = [&](const CalibrationResult& r) {
    double worst = 0;
    for (size_t i = 0; i < truth_.imus.size(); ++i) {
      const std::string& bone = truth_.skeleton.bone(truth_.imus[i].bone).name;
      if (bone.rfind("thigh", 0) == 0 || bone.rfind("shin", 0) == 0)
        worst = std::max(worst, AngleBetween(r.imus[i].mount, truth_.imus[i].mount));
    }
    return worst;
  };
  CalibrationResult free, hinged;
  std::string error;
  ASSERT_TRUE(CalibrateWindow(told_.skeleton, told_.rig, told_.layout, told_.imus, std::nullopt,
                              frames_, starts_, options_, &free, &error))
      << error;
  options_.joint_sigmas.assign(told_.skeleton.num_bones(), Eigen::Vector3d::Zero());
  for (int knee : knees) options_.joint_sigmas[knee] = Eigen::Vector3d(0.01, 0.0, 0.01);
  ASSERT_TRUE(CalibrateWindow(told_.skeleton, told_.rig, told_.layout, told_.imus, std::nullopt,
                              frames_, starts_, options_, &hinged, &error))
      << error;
  EXPECT_LT(leg_mount_error(hinged), 0.1 * kDeg);
  EXPECT_GT(leg_mount_error(free), 1.0 * kDeg);
}

TEST_F(WindowCalibrationTest, AHeldTPosePinsEveryMounting) {
  // The first frames are the rest pose (a T-pose), held: tied to it, every mounting comes
  // back whole; without it the limbs' twist stays where it started.
  for (int t = 0; t < 3; ++t) {
    thetas_[t].tail(thetas_[t].size() - 6).setZero();
    frames_[t] = testing::Render(truth_, thetas_[t], 0.1 * t);
  }
  auto worst_mount = [&](const CalibrationResult& r) {
    double worst = 0;
    for (size_t i = 0; i < truth_.imus.size(); ++i)
      worst = std::max(worst, AngleBetween(r.imus[i].mount, truth_.imus[i].mount));
    return worst;
  };
  CalibrationResult free, held;
  std::string error;
  ASSERT_TRUE(CalibrateWindow(told_.skeleton, told_.rig, told_.layout, told_.imus, std::nullopt,
                              frames_, starts_, options_, &free, &error))
      << error;
  for (int t = 0; t < 3; ++t) options_.held_poses.push_back({t, thetas_[t], 0.01});
  ASSERT_TRUE(CalibrateWindow(told_.skeleton, told_.rig, told_.layout, told_.imus, std::nullopt,
                              frames_, starts_, options_, &held, &error))
      << error;
  EXPECT_LT(worst_mount(held), 0.1 * kDeg);
  EXPECT_GT(worst_mount(free), 1.0 * kDeg);
}

TEST_F(WindowCalibrationTest, HeldParametersStayWhereTheyStart) {
  options_.estimate_headings = false;
  options_.estimate_scales = false;
  CalibrationResult r;
  std::string error;
  ASSERT_TRUE(CalibrateWindow(told_.skeleton, told_.rig, told_.layout, told_.imus, std::nullopt,
                              frames_, starts_, options_, &r, &error))
      << error;
  EXPECT_EQ(r.scales, std::vector<double>({1.0, 1.0}));
  for (size_t i = 0; i < told_.imus.size(); ++i)
    EXPECT_LT(AngleBetween(r.imus[i].reference, told_.imus[i].reference), 1e-12);
  // With the wrong headings and lengths held, the data cannot be met.
  EXPECT_GT(r.final_cost, 1.0);
}

// A performer who only turns on the spot: every bone turns about the vertical alone, so each
// IMU's readings are explained by any heading, its mounting's yaw taking up the difference
// (the product is all E_R sees). A heading prior (the accelerometer's, in use) settles it.
TEST_F(WindowCalibrationTest, AHeadingPriorSettlesWhatTurningOnTheSpotLeavesFree) {
  const Eigen::VectorXd base = thetas_[0];
  const Eigen::Matrix3d root = Exp(base.segment<3>(3));
  for (size_t t = 0; t < thetas_.size(); ++t) {
    thetas_[t] = base;
    thetas_[t].segment<3>(3) = Log(Exp(Eigen::Vector3d(0, 0, 0.05 * t)) * root);
    frames_[t] = testing::Render(truth_, thetas_[t], 0.1 * t);
    starts_[t] = testing::Perturb(thetas_[t], 0.05, 0.02, &rng_);
  }
  // The mountings start right, the headings 5 degrees off (as the heading search of
  // mocap.calibration.imus leaves them).
  for (size_t i = 0; i < told_.imus.size(); ++i) {
    told_.imus[i].mount = truth_.imus[i].mount;
    told_.imus[i].reference = Exp(Eigen::Vector3d(0, 0, 5 * kDeg)) * truth_.imus[i].reference;
  }
  // Worst heading error, or of the bone's axis in the sensor frame (deg); the twist of a pose
  // that never changes is not observed.
  auto worst = [&](const CalibrationResult& r, bool headings) {
    double w = 0;
    for (size_t i = 0; i < truth_.imus.size(); ++i) {
      const ImuSite &got = r.imus[i], &want = truth_.imus[i];
      const double along = std::min(
          1.0, AxisInSensor(truth_.skeleton, got).dot(AxisInSensor(truth_.skeleton, want)));
      w = std::max(w, headings ? AngleBetween(got.reference, want.reference) : std::acos(along));
    }
    return w / kDeg;
  };
  CalibrationResult free, settled;
  std::string error;
  ASSERT_TRUE(CalibrateWindow(told_.skeleton, told_.rig, told_.layout, told_.imus, std::nullopt,
                              frames_, starts_, options_, &free, &error))
      << error;
  for (const ImuSite& s : truth_.imus)
    options_.heading_priors.emplace_back(std::atan2(s.reference(1, 0), s.reference(0, 0)),
                                         1.0 * kDeg);
  ASSERT_TRUE(CalibrateWindow(told_.skeleton, told_.rig, told_.layout, told_.imus, std::nullopt,
                              frames_, starts_, options_, &settled, &error))
      << error;
  // Measured: free 3.0 and 2.5 degrees (part way back from the start's 5); settled 0.0 and
  // 0.2 (the back: no keypoint tells how the spine's bend is shared between its two bones).
  EXPECT_GT(worst(free, true), 2.0);
  EXPECT_GT(worst(free, false), 1.5);
  EXPECT_LT(worst(settled, true), 0.05);
  EXPECT_LT(worst(settled, false), 0.5);  // the bone's axis in the sensor frame
  options_.heading_priors.assign(3, Eigen::Vector2d(0.0, 1.0));
  EXPECT_FALSE(CalibrateWindow(told_.skeleton, told_.rig, told_.layout, told_.imus, std::nullopt,
                               frames_, starts_, options_, &settled, &error));
  EXPECT_NE(error.find("heading_priors"), std::string::npos) << error;
}

// The detector's sites 2 cm from the layout's, the true skeleton and IMUs held: sites are
// estimated only along the directions the window observes (standard deviation under 1 cm
// for 5 px keypoints). Varied poses observe nearly all and bring the sites back; a performer
// standing still observes fewer, and those changes do not take the sites further from the
// truth than the layout's.
TEST_F(WindowCalibrationTest, SitesMoveOnlyAlongObservedDirections) {
  testing::Scene detector = truth_;
  for (Site& s : detector.layout.sites) s.offset += 0.02 * Eigen::Vector3d::Random().normalized();
  options_.estimate_scales = options_.estimate_shifts = false;
  options_.estimate_mounts = options_.estimate_headings = false;
  options_.estimate_sites = true;
  options_.site_sigma = 0.03;
  options_.site_observable_std = 0.01;
  auto mean_site_error = [&](const KeypointLayout& layout) {
    double sum = 0;
    for (int k = 0; k < layout.size(); ++k)
      sum += (layout.sites[k].offset - detector.layout.sites[k].offset).norm();
    return sum / layout.size();
  };
  const int n = 3 * truth_.layout.size();
  // Without a prior the poses' unobserved DOF (toe twist, ...) leave the covariance undefined;
  // this one costs nothing at the true poses.
  const PosePrior prior = testing::PriorThrough(thetas_, 40, &rng_);
  auto calibrate = [&](const std::vector<Eigen::VectorXd>& poses) {
    std::vector<FrameObservations> frames;
    std::vector<Eigen::VectorXd> starts;
    for (size_t t = 0; t < poses.size(); ++t) {
      frames.push_back(testing::Render(detector, poses[t], 0.1 * t));
      starts.push_back(testing::Perturb(poses[t], 0.05, 0.02, &rng_));
    }
    CalibrationResult r;
    std::string error;
    EXPECT_TRUE(CalibrateWindow(truth_.skeleton, truth_.rig, truth_.layout, truth_.imus, prior,
                                frames, starts, options_, &r, &error))
        << error;
    return r;
  };
  const CalibrationResult varied = calibrate(thetas_);
  // Measured: 98 of 99 directions, 0.8 mm; standing still 90, 6.7 mm (from 21 mm).
  EXPECT_GT(varied.site_directions_kept, 0.95 * n);
  EXPECT_LT(mean_site_error(varied.layout), 0.002);
  const CalibrationResult still = calibrate(std::vector<Eigen::VectorXd>(30, thetas_[0]));
  EXPECT_LT(still.site_directions_kept, varied.site_directions_kept);
  EXPECT_LE(mean_site_error(still.layout), mean_site_error(truth_.layout) + 0.001);
  // The kept directions are orthonormal, and along them the sites are where the detector's
  // are (standing still too: the error left is along what the window does not see).
  const Eigen::MatrixXd& d = still.site_directions;
  ASSERT_EQ(d.rows(), n);
  ASSERT_EQ(d.cols(), still.site_directions_kept);
  EXPECT_LT((d.transpose() * d - Eigen::MatrixXd::Identity(d.cols(), d.cols())).norm(), 1e-9);
  auto along_kept = [&](const KeypointLayout& layout) {
    Eigen::VectorXd e(n);
    for (int k = 0; k < layout.size(); ++k)
      e.segment<3>(3 * k) = layout.sites[k].offset - detector.layout.sites[k].offset;
    return (d.transpose() * e).norm();
  };
  // Measured: 2.0 mm against the layout's 107 mm (root-sum-square over the kept directions).
  EXPECT_LT(along_kept(still.layout), 0.05 * along_kept(truth_.layout));
}

TEST_F(WindowCalibrationTest, InconsistentInputsAreRefused) {
  CalibrationResult r;
  std::string error;
  std::vector<Eigen::VectorXd> fewer(starts_.begin(), starts_.end() - 1);
  EXPECT_FALSE(CalibrateWindow(told_.skeleton, told_.rig, told_.layout, told_.imus, std::nullopt,
                               frames_, fewer, options_, &r, &error));
  EXPECT_NE(error.find("one starting pose per frame"), std::string::npos) << error;
  std::vector<Eigen::VectorXd> bad = starts_;
  bad[3](10) = NAN;
  EXPECT_FALSE(CalibrateWindow(told_.skeleton, told_.rig, told_.layout, told_.imus, std::nullopt,
                               frames_, bad, options_, &r, &error));
  EXPECT_NE(error.find("starting pose 3"), std::string::npos) << error;
  options_.scale_group.pop_back();
  EXPECT_FALSE(CalibrateWindow(told_.skeleton, told_.rig, told_.layout, told_.imus, std::nullopt,
                               frames_, starts_, options_, &r, &error));
  EXPECT_NE(error.find("scale_group"), std::string::npos) << error;
  options_.scale_group = group_;
  options_.joint_sigmas.assign(3, Eigen::Vector3d::Zero());
  EXPECT_FALSE(CalibrateWindow(told_.skeleton, told_.rig, told_.layout, told_.imus, std::nullopt,
                               frames_, starts_, options_, &r, &error));
  EXPECT_NE(error.find("joint_sigmas"), std::string::npos) << error;
  options_.joint_sigmas.clear();
  options_.held_poses = {{static_cast<int>(frames_.size()), thetas_[0], 0.05}};
  EXPECT_FALSE(CalibrateWindow(told_.skeleton, told_.rig, told_.layout, told_.imus, std::nullopt,
                               frames_, starts_, options_, &r, &error));
  EXPECT_NE(error.find("held pose"), std::string::npos) << error;
  EXPECT_FALSE(CalibrateWindow(told_.skeleton, told_.rig, told_.layout, told_.imus, std::nullopt,
                               {}, {}, CalibrationOptions(), &r, &error));
  EXPECT_NE(error.find("no frames"), std::string::npos) << error;
}

TEST_F(WindowCalibrationTest, MalformedObservationsAreDroppedNotFatal) {
  // NaN keypoints and a non-unit quaternion in a few frames: counted out, the rest calibrates.
  for (int t = 0; t < 5; ++t) {
    frames_[t].cameras[0].keypoints[3].x = NAN;
    frames_[t].imus[0].orientation.coeffs() *= 3.0;
  }
  CalibrationResult r;
  std::string error;
  ASSERT_TRUE(CalibrateWindow(told_.skeleton, told_.rig, told_.layout, told_.imus, std::nullopt,
                              frames_, starts_, options_, &r, &error))
      << error;
  EXPECT_NEAR(r.scales[0], 1.06, 1e-4);
  EXPECT_LT(AngleBetween(r.imus[0].reference, truth_.imus[0].reference), 0.05 * kDeg);
}

}  // namespace
}  // namespace mocap
