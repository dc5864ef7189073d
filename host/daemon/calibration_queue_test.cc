// Calibrations are checked on arrival (the solver's own check, the session's layout and
// IMU set), taken once per source sequence, and handed over in order of their valid time.
#include "calibration_queue.h"

#include <gtest/gtest.h>

#include "synthetic_scene.h"

namespace mocap {
namespace {

v1::Calibration CalibrationOf(const testing::Scene& scene, int64_t valid_from_ns, uint64_t sequence,
                              const std::string& source = "calibrator") {
  v1::Calibration c;
  c.set_source(source);
  c.set_sequence(sequence);
  c.set_valid_from_ns(valid_from_ns);
  c.set_skeleton_json(SkeletonToJson(scene.skeleton));
  c.set_imus_json(ImuSitesToJson(scene.skeleton, scene.imus));
  c.set_layout_json(KeypointLayoutToJson(scene.skeleton, scene.layout));
  return c;
}

struct QueueTest : ::testing::Test {
  testing::Scene scene = testing::MakeScene(2);
  std::unique_ptr<Solver> solver;
  CalibrationQueue queue;
  void SetUp() override {
    std::string error;
    solver = Solver::Create(scene.skeleton, scene.rig, scene.layout, scene.imus, std::nullopt,
                            SolverOptions(), &error);
    ASSERT_TRUE(solver) << error;
  }
};

TEST_F(QueueTest, CalibrationsAreDueInOrderOfTheirValidTime) {
  std::string error;
  for (const auto& [t, sequence] :
       std::vector<std::pair<int64_t, uint64_t>>{{30, 1}, {10, 2}, {20, 3}})
    ASSERT_TRUE(queue.Add(CalibrationOf(scene, t, sequence), *solver, &error)) << error;
  EXPECT_TRUE(queue.TakeDue(9).empty());
  const std::vector<PendingCalibration> first = queue.TakeDue(15);
  ASSERT_EQ(first.size(), 1u);
  EXPECT_EQ(first[0].valid_from_ns, 10);
  const std::vector<PendingCalibration> rest = queue.TakeDue(30);
  ASSERT_EQ(rest.size(), 2u);
  EXPECT_EQ(rest[0].valid_from_ns, 20);
  EXPECT_EQ(rest[1].valid_from_ns, 30);
  EXPECT_EQ(queue.size(), 0u);
}

TEST_F(QueueTest, ARepeatOfASourcesSequenceIsTakenOnce) {
  std::string error;
  EXPECT_TRUE(queue.Add(CalibrationOf(scene, 10, 4), *solver, &error));
  EXPECT_TRUE(queue.Add(CalibrationOf(scene, 10, 4), *solver, &error));
  EXPECT_TRUE(queue.Add(CalibrationOf(scene, 20, 3), *solver, &error));
  EXPECT_TRUE(queue.Add(CalibrationOf(scene, 10, 0, "other"), *solver, &error));
  EXPECT_EQ(queue.size(), 2u);
  EXPECT_EQ(queue.counts().repeated, 2u);
}

TEST_F(QueueTest, ACalibrationThatDoesNotFitIsRejectedWithTheReason) {
  testing::Scene renamed = scene;
  std::vector<Skeleton::Bone> bones = renamed.skeleton.bones();
  bones[4].name = "tail";
  std::string error;
  ASSERT_TRUE(Skeleton::Create(bones, &renamed.skeleton, &error)) << error;
  testing::Scene stranger = scene;
  stranger.imus[2].name = "stranger";
  const testing::Scene other_layout = testing::MakeScene(2, "coco17");
  v1::Calibration broken = CalibrationOf(scene, 0, 0);
  broken.set_imus_json("{\"format\": \"mocap.imus/1\", \"imus\": [");
  const std::vector<std::pair<v1::Calibration, std::string>> cases = {
      {CalibrationOf(renamed, 0, 0), "tail"},
      {CalibrationOf(stranger, 0, 0), "stranger"},
      {CalibrationOf(other_layout, 0, 0), "coco17"},
      {broken, ""}};
  for (const auto& [calibration, reason] : cases) {
    EXPECT_FALSE(queue.Add(calibration, *solver, &error)) << reason;
    EXPECT_NE(error.find(reason), std::string::npos) << error;
  }
  EXPECT_EQ(queue.size(), 0u);
  EXPECT_EQ(queue.counts().rejected, 4u);
  queue.CountApplied(false);
  queue.CountApplied(true);
  EXPECT_EQ(queue.counts().rejected, 5u);
  EXPECT_EQ(queue.counts().applied, 1u);
}

TEST_F(QueueTest, SensorsACalibrationLeavesOutKeepTheirPlaceUncalibrated) {
  testing::Scene partial = scene;
  for (ImuSite& s : partial.imus) s.mount = Eigen::Matrix3d::Identity();
  partial.imus.erase(partial.imus.begin() + 5);
  std::string error;
  ASSERT_TRUE(queue.Add(CalibrationOf(partial, 0, 0), *solver, &error)) << error;
  const PendingCalibration p = queue.TakeDue(0).at(0);
  ASSERT_EQ(p.imus.size(), scene.imus.size());
  for (size_t i = 0; i < p.imus.size(); ++i) {
    EXPECT_EQ(p.imus[i].name, scene.imus[i].name);
    EXPECT_EQ(p.calibrated[i], i != 5) << i;
    EXPECT_EQ(p.imus[i].mount.isIdentity(1e-12), i != 5) << i;  // the calibration's, or kept
  }
}

// A calibrator's JSON with a value of the wrong type where a string or number is read (the
// format, a name, the reference height) is refused with an error: the readers threw, and the
// exception would have ended mocapd.
TEST_F(QueueTest, FieldsOfTheWrongTypeAreRefusedNotThrown) {
  using Field = std::string* (v1::Calibration::*)();
  const std::vector<std::pair<Field, std::string>> cases = {
      {&v1::Calibration::mutable_skeleton_json, R"({"format": 1, "bones": []})"},
      {&v1::Calibration::mutable_layout_json,
       R"({"format": "mocap.layout/1", "keypoints": [], "name": 3})"},
      {&v1::Calibration::mutable_layout_json,
       R"({"format": "mocap.layout/1", "keypoints": [], "reference_height": "x"})"},
      {&v1::Calibration::mutable_imus_json,
       R"({"format": "mocap.imus/1", "imus": [{"name": 7}]})"}};
  for (const auto& [field, json] : cases) {
    v1::Calibration c = CalibrationOf(scene, 0, 1);
    *(c.*field)() = json;
    std::string error;
    EXPECT_FALSE(queue.Add(c, *solver, &error)) << json;
    EXPECT_NE(error.find("malformed field"), std::string::npos) << error;
  }
}

}  // namespace
}  // namespace mocap
