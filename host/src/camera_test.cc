#include "mocap/camera.h"

#include <gtest/gtest.h>

#include "mocap/so3.h"

namespace mocap {
namespace {

Camera TestCamera() {
  Camera c;
  c.name = "c";
  c.width = 1920;
  c.height = 1080;
  c.fx = 1500;
  c.fy = 1490;
  c.cx = 950;
  c.cy = 545;
  c.distortion = {-0.2, 0.08, 0.001, -0.0015, -0.01};
  c.rotation = Exp(Eigen::Vector3d(0.1, -0.2, 0.05));
  c.translation = Eigen::Vector3d(0.2, -0.1, 4.0);
  return c;
}

TEST(Camera, ProjectsHandComputedPoint) {
  Camera c;
  c.width = 100;
  c.height = 100;
  c.fx = 100;
  c.fy = 200;
  c.cx = 50;
  c.cy = 40;
  c.distortion = {0.1, 0, 0, 0, 0};
  // Camera at the origin looking along +z: X = (1, 0, 2) -> u = 0.5, r2 = 0.25, radial 1.025
  Eigen::Vector2d px;
  ASSERT_TRUE(c.Project(Eigen::Vector3d(1, 0, 2), &px));
  EXPECT_NEAR(px.x(), 100 * 0.5 * 1.025 + 50, 1e-12);
  EXPECT_NEAR(px.y(), 40, 1e-12);
}

TEST(Camera, RefusesPointsBehind) {
  const Camera c = TestCamera();
  Eigen::Vector2d px(-1, -1);
  const Eigen::Vector3d behind =
      c.rotation.transpose() * (Eigen::Vector3d(0, 0, -1) - c.translation);
  EXPECT_FALSE(c.Project(behind, &px));
  EXPECT_EQ(px.x(), -1);
}

TEST(Camera, JacobianMatchesFiniteDifferences) {
  const Camera c = TestCamera();
  const Eigen::Vector3d x(0.3, 0.4, 0.5);
  Eigen::Vector2d px;
  Eigen::Matrix<double, 2, 3> j;
  ASSERT_TRUE(c.Project(x, &px, &j));
  for (int k = 0; k < 3; ++k) {
    const double h = 1e-6;
    Eigen::Vector2d p2;
    ASSERT_TRUE(c.Project(x + h * Eigen::Vector3d::Unit(k), &p2));
    EXPECT_LT(((p2 - px) / h - j.col(k)).norm(), 1e-3);  // pixels per metre, ~1e3 scale
  }
}

TEST(Camera, UndistortInvertsProjection) {
  const Camera c = TestCamera();
  const Eigen::Vector3d x(-0.6, 0.5, 0.2);
  Eigen::Vector2d px;
  ASSERT_TRUE(c.Project(x, &px));
  const Eigen::Vector3d xc = c.rotation * x + c.translation;
  EXPECT_LT((c.Undistort(px) - xc.head<2>() / xc.z()).norm(), 1e-9);
}

TEST(Rig, JsonRoundTrips) {
  Rig rig;
  rig.cameras.push_back(TestCamera());
  Rig again;
  std::string error;
  ASSERT_TRUE(ParseRigJson(RigToJson(rig), &again, &error)) << error;
  ASSERT_EQ(again.cameras.size(), 1u);
  EXPECT_LT((again.cameras[0].rotation - rig.cameras[0].rotation).norm(), 1e-12);
  EXPECT_EQ(again.cameras[0].distortion[4], -0.01);
}

TEST(Camera, RefusesImplausibleDistortion) {
  std::string error;
  Camera c = TestCamera();
  ASSERT_TRUE(c.IsValid(&error)) << error;
  c.distortion = {-0.3, 0.1, 0.0, 0.0, 0.0};  // a wide-angle lens: kept
  EXPECT_TRUE(c.IsValid(&error)) << error;
  c.distortion = {1e6, 0, 0, 0, 0};  // moved pixels by metres, unnoticed, before the check
  EXPECT_FALSE(c.IsValid(&error));
  EXPECT_NE(error.find("camera 'c': implausible distortion (a radial factor"), std::string::npos)
      << error;
  c.distortion = {-1.5, 0, 0, 0, 0};  // r (1 - 1.5 r^2) turns back inside the image
  EXPECT_FALSE(c.IsValid(&error));
  c.distortion = {-0.2, 0.08, 0.2, 0, 0};
  EXPECT_FALSE(c.IsValid(&error));
  EXPECT_NE(error.find("tangential"), std::string::npos) << error;
}

}  // namespace
}  // namespace mocap
