// Suits found on the people wearing them from motion alone: the sensors' mountings and
// heading references are unknown to the matcher, the subjects' poses are noisy, yet each
// suit is decided for its wearer once the window is full, nobody is decided while everyone
// stands still, a wearer whose solve is poor is found all the same (by when their turns happen),
// and two suits swapped between their wearers mid-take are found on their new
// wearers (and counted).
#include "mocap/suit_matcher.h"

#include <gtest/gtest.h>

#include <random>

#include "mocap/so3.h"
#include "synthetic_scene.h"

namespace mocap {
namespace {

constexpr double kDt = 1.0 / 60.0;

// A smooth motion: each joint DOF a sum of two sinusoids of its own.
struct Motion {
  Eigen::MatrixXd amplitude, frequency, phase;  // (dof, 2)
  Motion(int dof, std::mt19937* rng) : amplitude(dof, 2), frequency(dof, 2), phase(dof, 2) {
    std::uniform_real_distribution<double> a(0.1, 0.5), f(0.3, 1.5), p(0, 6.3);
    for (int i = 0; i < dof; ++i)
      for (int k = 0; k < 2; ++k)
        amplitude(i, k) = a(*rng), frequency(i, k) = f(*rng), phase(i, k) = p(*rng);
  }
  Eigen::VectorXd At(double t, double scale = 1.0) const {
    Eigen::VectorXd theta = Eigen::VectorXd::Zero(amplitude.rows());
    for (int i = 3; i < theta.size(); ++i)
      for (int k = 0; k < 2; ++k)
        theta[i] +=
            scale * amplitude(i, k) * std::sin(2 * M_PI * frequency(i, k) * t + phase(i, k));
    return theta;
  }
};

Eigen::Matrix3d RandomRotation(std::mt19937* rng) {
  std::normal_distribution<double> n(0, 1);
  return Exp(Eigen::Vector3d(n(*rng), n(*rng), n(*rng)));
}

struct Suit {
  std::vector<int> bones;
  std::vector<Eigen::Matrix3d> mount, reference;
};

Suit MakeSuit(const testing::Scene& scene, std::mt19937* rng) {
  Suit suit;
  for (const ImuSite& site : scene.imus) {
    suit.bones.push_back(site.bone);
    suit.mount.push_back(RandomRotation(rng));
    suit.reference.push_back(RandomRotation(rng));
  }
  return suit;
}

// The suit's readings on a body, R_i = reference^T * G_bone * mount.
std::vector<Eigen::Quaterniond> Readings(const Suit& suit, const BodyPose& body) {
  std::vector<Eigen::Quaterniond> q;
  for (size_t i = 0; i < suit.bones.size(); ++i)
    q.emplace_back(suit.reference[i].transpose() * body.rotation[suit.bones[i]] * suit.mount[i]);
  return q;
}

// Every bone's rotation off by a random ~noise_deg turn: a solve from video.
BodyPose Noisy(BodyPose body, double noise_deg, std::mt19937* rng) {
  std::normal_distribution<double> n(0, noise_deg * M_PI / 180.0);
  for (Eigen::Matrix3d& r : body.rotation) r = r * Exp(Eigen::Vector3d(n(*rng), n(*rng), n(*rng)));
  return body;
}

class SuitMatcherTest : public ::testing::Test {
 protected:
  SuitMatcherTest() : scene_(testing::MakeScene(4)), rng_(21) {
    for (int p = 0; p < 3; ++p) motions_.emplace_back(scene_.skeleton.pose_dim(), &rng_);
    for (int s = 0; s < 2; ++s) suits_.push_back(MakeSuit(scene_, &rng_));
  }

  // Frames [first, last): subjects 1-3 perform motions 0-2 (a fourth, if any, is out of view); suit
  // s is worn by performer worn_by[s]; motion scaled by `scale` (0: everyone still).
  void Run(SuitMatcher* matcher, int first, int last, const std::vector<int>& worn_by,
           double scale = 1.0) {
    for (int f = first; f < last; ++f) {
      std::vector<BodyPose> truth(motions_.size());  // beyond the third: out of view
      std::map<uint32_t, BodyPose> solved;
      for (size_t p = 0; p < motions_.size(); ++p) {
        ForwardKinematics(scene_.skeleton, motions_[p].At(f * kDt, scale).data(), &truth[p]);
        if (p < 3) solved[p + 1] = Noisy(truth[p], noise_deg_, &rng_);
      }
      std::vector<std::vector<Eigen::Quaterniond>> readings;
      for (size_t s = 0; s < suits_.size(); ++s)
        readings.push_back(Readings(suits_[s], truth[worn_by[s]]));
      matcher->Add(f * kDt, solved, readings);
    }
  }

  std::vector<std::vector<int>> Bones() const { return {suits_[0].bones, suits_[1].bones}; }

  testing::Scene scene_;
  std::mt19937 rng_;
  double noise_deg_ = 3.0;  // of the subjects' solves
  std::vector<Motion> motions_;
  std::vector<Suit> suits_;
};

TEST_F(SuitMatcherTest, EachSuitIsFoundOnItsWearerOnceTheWindowIsFull) {
  SuitMatcher matcher(Bones(), SuitMatchOptions{});
  Run(&matcher, 0, 110, {2, 0});  // under the window's 2 s: undecided
  EXPECT_EQ(matcher.wearers(), (std::vector<uint32_t>{0, 0}));
  Run(&matcher, 110, 130, {2, 0});
  EXPECT_EQ(matcher.wearers(), (std::vector<uint32_t>{3, 1}));
  const auto d = matcher.Disagreements(0);
  EXPECT_LT(d.at(3) + 0.03, std::min(d.at(1), d.at(2)));
  EXPECT_EQ(matcher.changes(), 0u);
}

TEST_F(SuitMatcherTest, EachSuitLeadsForItsWearerLongBeforeItIsDecided) {
  SuitMatcher matcher(Bones(), SuitMatchOptions{});
  Run(&matcher, 0, SuitMatcher::kMinLeadingFrames + 6, {2, 0});  // 0.1 s of turns, then a few
  EXPECT_EQ(matcher.wearers(), (std::vector<uint32_t>{0, 0}));
  EXPECT_EQ(matcher.leaders(), (std::vector<uint32_t>{3, 1}));
  Run(&matcher, SuitMatcher::kMinLeadingFrames + 6, 130, {2, 0});
  EXPECT_EQ(matcher.leaders(), matcher.wearers());
  matcher.Forget(0, 3);  // a suit taken off leads for nobody until measured again
  EXPECT_EQ(matcher.leaders()[0], 0u);
}

TEST_F(SuitMatcherTest, NobodyLeadsWhileEveryoneStandsStill) {
  SuitMatcher matcher(Bones(), SuitMatchOptions{});
  Run(&matcher, 0, 300, {2, 0}, 0.0);
  EXPECT_EQ(matcher.leaders(), (std::vector<uint32_t>{0, 0}));
}

TEST_F(SuitMatcherTest, NothingIsDecidedWhileEveryoneStandsStill) {
  SuitMatcher matcher(Bones(), SuitMatchOptions{});
  Run(&matcher, 0, 300, {2, 0}, 0.0);
  EXPECT_EQ(matcher.wearers(), (std::vector<uint32_t>{0, 0}));
}

TEST_F(SuitMatcherTest, SuitsSwappedBetweenTheirWearersAreFoundOnTheNewOnes) {
  SuitMatcher matcher(Bones(), SuitMatchOptions{});
  Run(&matcher, 0, 240, {2, 0});
  ASSERT_EQ(matcher.wearers(), (std::vector<uint32_t>{3, 1}));
  Run(&matcher, 240, 480, {0, 2});  // swapped at 4 s
  EXPECT_EQ(matcher.wearers(), (std::vector<uint32_t>{1, 3}));
  EXPECT_EQ(matcher.changes(), 2u);
}

TEST_F(SuitMatcherTest, ASuitNobodyInViewWearsStaysOnNobody) {
  // Suit 0 on a fourth person the cameras do not see (a motion of their own), suit 1 on performer
  // 0.
  motions_.emplace_back(scene_.skeleton.pose_dim(), &rng_);
  SuitMatcher matcher(Bones(), SuitMatchOptions{});
  Run(&matcher, 0, 300, {3, 0});
  EXPECT_EQ(matcher.wearers(), (std::vector<uint32_t>{0, 1}));
  for (const auto& [id, d] : matcher.Disagreements(0))
    EXPECT_GT(d, SuitMatchOptions{}.gate_rad) << id;
}

TEST_F(SuitMatcherTest, AWearerSolvedPoorlyIsFoundByWhenTheirTurnsHappen) {
  noise_deg_ = 10.0;  // every subject's bones: their turns over 0.1 s off by far more than the gate
  SuitMatcher matcher(Bones(), SuitMatchOptions{});
  Run(&matcher, 0, 200, {2, 0});
  const auto d = matcher.Disagreements(0);
  EXPECT_GT(d.at(3), SuitMatchOptions{}.gate_rad);
  EXPECT_EQ(matcher.wearers(), (std::vector<uint32_t>{3, 1}));
  EXPECT_EQ(matcher.changes(), 0u);
}

TEST_F(SuitMatcherTest, ASuitNobodyInViewWearsStaysOnNobodyWhenTheSolvesArePoor) {
  noise_deg_ = 10.0;
  motions_.emplace_back(scene_.skeleton.pose_dim(), &rng_);
  SuitMatcher matcher(Bones(), SuitMatchOptions{});
  Run(&matcher, 0, 300, {3, 0});
  EXPECT_EQ(matcher.wearers(), (std::vector<uint32_t>{0, 1}));
}

TEST_F(SuitMatcherTest, AWearerWhoLeavesLeavesTheSuitOnNobody) {
  SuitMatcher matcher(Bones(), SuitMatchOptions{});
  Run(&matcher, 0, 200, {2, 0});
  ASSERT_EQ(matcher.wearers()[0], 3u);
  BodyPose body;
  ForwardKinematics(scene_.skeleton, motions_[0].At(0).data(), &body);
  matcher.Add(200 * kDt, {{1, body}}, {Readings(suits_[0], body), Readings(suits_[1], body)});
  EXPECT_EQ(matcher.wearers()[0], 0u);
  EXPECT_THROW(matcher.Add(201 * kDt, {}, {}), std::invalid_argument);
  SuitMatchOptions bad;
  bad.baseline_s = 5.0;
  EXPECT_THROW(SuitMatcher(Bones(), bad), std::invalid_argument);
  bad = SuitMatchOptions{};
  bad.lock_ratio = 1.5;
  EXPECT_THROW(SuitMatcher(Bones(), bad), std::invalid_argument);
}

}  // namespace
}  // namespace mocap
