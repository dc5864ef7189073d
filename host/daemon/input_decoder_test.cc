// Wire messages to synchroniser inputs: ids mapped to the session's cameras and IMUs,
// persons checked against the layout, IMU status bits and quaternion order.
#include "input_decoder.h"

#include <gtest/gtest.h>

#include "synthetic_scene.h"

namespace mocap {
namespace {

struct DecoderTest : ::testing::Test {
  testing::Scene scene = testing::MakeScene(2, "coco17");
  InputDecoder decoder{scene.rig, scene.imus, scene.layout};

  v1::KeypointFrame Frame(int camera, int persons, int keypoints = 17) const {
    v1::KeypointFrame f;
    f.set_camera_id(scene.rig.cameras[camera].name);
    f.set_capture_time_ns(123);
    f.set_keypoint_layout("coco17");
    f.set_detected(true);
    for (int p = 0; p < persons; ++p) {
      v1::KeypointPerson* person = f.add_persons();
      for (int k = 0; k < keypoints; ++k)
        person->add_x(100 * p + k), person->add_y(k), person->add_confidence(0.5f);
    }
    return f;
  }
};

TEST_F(DecoderTest, AFrameBecomesItsCamerasInputWithTheSubjectsKeypoints) {
  const v1::KeypointFrame f = Frame(1, 2);
  int camera = -1;
  Rejection why;
  ASSERT_TRUE(decoder.CameraOf(f, &camera, &why)) << why.detail;
  EXPECT_EQ(camera, 1);
  const CameraInput in = decoder.ToCameraInput(f, camera, 1);
  EXPECT_EQ(in.camera, 1);
  EXPECT_EQ(in.time_ns, 123);
  ASSERT_EQ(in.keypoints.size(), 17u);
  EXPECT_EQ(in.keypoints[3].x, 103);
  EXPECT_EQ(in.keypoints[3].y, 3);
  EXPECT_DOUBLE_EQ(in.keypoints[3].confidence, 0.5);
}

TEST_F(DecoderTest, AFrameWithoutDetectionClocksTheSolveWithoutKeypoints) {
  v1::KeypointFrame f = Frame(0, 1, 5);  // the count is not checked: nothing is read
  f.set_detected(false);
  int camera = -1;
  Rejection why;
  ASSERT_TRUE(decoder.CameraOf(f, &camera, &why));
  const CameraInput in = decoder.ToCameraInput(f, camera, -1);
  EXPECT_FALSE(in.detected);
  EXPECT_TRUE(in.keypoints.empty());
}

TEST_F(DecoderTest, StrangersAndOtherLayoutsAreRejectedWithTheirReason) {
  int camera = -1;
  Rejection why;
  v1::KeypointFrame stranger = Frame(0, 1);
  stranger.set_camera_id("cam99");
  EXPECT_FALSE(decoder.CameraOf(stranger, &camera, &why));
  EXPECT_EQ(why.reason, "unknown_source");
  EXPECT_NE(why.detail.find("cam99"), std::string::npos);
  v1::KeypointFrame other = Frame(1, 1);
  other.set_keypoint_layout("blazepose33");
  EXPECT_FALSE(decoder.CameraOf(other, &camera, &why));
  EXPECT_EQ(why.reason, "invalid");
  EXPECT_EQ(camera, 1);  // known: its statistics count it
  EXPECT_FALSE(decoder.CameraOf(Frame(0, 2, 16), &camera, &why));
  EXPECT_EQ(why.reason, "invalid");
}

TEST_F(DecoderTest, SamplesMapToTheImuSetWithQuaternionsWFirst) {
  EXPECT_EQ(decoder.ImuOf(scene.imus[4].name), 4);
  EXPECT_EQ(decoder.ImuOf("stranger"), -1);
  v1::ImuSample s;
  s.set_sample_time_ns(5);
  s.set_qw(0.5), s.set_qx(0.5), s.set_qy(-0.5), s.set_qz(0.5);
  s.set_ax(1), s.set_ay(2), s.set_az(3);
  s.set_status(v1::ImuSample::STATUS_ACCELERATION_INVALID);
  const ImuInput in = InputDecoder::ToImuInput(s, 4);
  EXPECT_EQ(in.imu, 4);
  EXPECT_EQ(in.time_ns, 5);
  EXPECT_EQ(in.orientation.coeffs(), Eigen::Vector4d(0.5, -0.5, 0.5, 0.5));  // x, y, z, w
  EXPECT_EQ(in.acceleration, Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(in.has_orientation);
  EXPECT_FALSE(in.has_acceleration);
  s.set_status(v1::ImuSample::STATUS_ORIENTATION_INVALID);
  EXPECT_FALSE(InputDecoder::ToImuInput(s, 4).has_orientation);
}

}  // namespace
}  // namespace mocap
