#include "mocap/so3.h"

#include <gtest/gtest.h>

#include <random>

namespace mocap {
namespace {

constexpr double kTol = 1e-9;
constexpr double kNumericTol = 1e-6;

TEST(So3, ExpMatchesEigenAngleAxis) {
  const Eigen::Vector3d w(0.3, -1.2, 0.7);
  const Eigen::Matrix3d expected = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
  EXPECT_LT((Exp(w) - expected).norm(), kTol);
}

TEST(So3, LogInvertsExpIncludingNearZeroAndNearPi) {
  for (const Eigen::Vector3d& w :
       {Eigen::Vector3d(1e-9, 0, 0), Eigen::Vector3d(0.2, 0.1, -0.3),
        Eigen::Vector3d(0, 0, M_PI - 1e-7), Eigen::Vector3d(1.0, 2.0, 0.5)}) {
    EXPECT_LT((Log(Exp(w)) - w).norm(), 1e-7) << w.transpose();
  }
}

TEST(So3, RightJacobiansMatchFiniteDifferences) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Vector3d w(u(rng), u(rng), u(rng));
    const Eigen::Matrix3d jr = RightJacobian(w);
    const Eigen::Matrix3d jr_inv = InverseRightJacobian(w);
    EXPECT_LT((jr * jr_inv - Eigen::Matrix3d::Identity()).norm(), kTol);
    for (int k = 0; k < 3; ++k) {
      const double h = 1e-6;
      const Eigen::Vector3d d = h * Eigen::Vector3d::Unit(k);
      // Exp(w + d) = Exp(w) Exp(Jr d)
      const Eigen::Vector3d numeric = Log(Exp(w).transpose() * Exp(w + d)) / h;
      EXPECT_LT((numeric - jr.col(k)).norm(), kNumericTol);
      // Log(Exp(w) Exp(d)) = w + Jr^-1 d
      const Eigen::Vector3d numeric_inv = (Log(Exp(w) * Exp(d)) - w) / h;
      EXPECT_LT((numeric_inv - jr_inv.col(k)).norm(), kNumericTol);
    }
  }
}

TEST(So3, AngleBetweenIsGeodesic) {
  const Eigen::Matrix3d a = Exp(Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_NEAR(AngleBetween(a, a * Exp(Eigen::Vector3d(0, 0.25, 0))), 0.25, kTol);
}

}  // namespace
}  // namespace mocap
