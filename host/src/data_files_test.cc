// The shipped data files load, and malformed files are refused with a message.
#include <gtest/gtest.h>

#include "mocap/camera.h"
#include "mocap/prior.h"
#include "mocap/sites.h"
#include "mocap/skeleton.h"
#include "synthetic_scene.h"

namespace mocap {
namespace {

using testing::DataPath;

TEST(DataFiles, DefaultSkeletonIsThePapersSkeleton) {
  Skeleton s;
  std::string error;
  ASSERT_TRUE(LoadSkeletonJson(DataPath("skeleton_default.json"), &s, &error)) << error;
  ASSERT_EQ(s.num_bones(), 21);
  EXPECT_EQ(s.pose_dim(), 66);
  for (int b = 0; b < 21; ++b) EXPECT_EQ(s.bone(b).name, kCanonicalBoneNames[b]);
  EXPECT_NEAR(s.RestHeight(), 1.53, 0.01);  // pelvis-to-head-joint-to-toes extent of a 1.75 m adult
  Skeleton again;
  ASSERT_TRUE(ParseSkeletonJson(SkeletonToJson(s), &again, &error)) << error;
  EXPECT_EQ(again.bone(20).parent, s.bone(20).parent);
  EXPECT_LT((again.bone(7).offset - s.bone(7).offset).norm(), 1e-12);
}

TEST(DataFiles, LayoutsHaveTheirDetectorsKeypointCounts) {
  Skeleton s;
  std::string error;
  ASSERT_TRUE(LoadSkeletonJson(DataPath("skeleton_default.json"), &s, &error));
  for (const auto& [name, count] :
       {std::pair<std::string, int>{"coco17", 17}, {"body25b", 25}, {"blazepose33", 33}}) {
    KeypointLayout layout;
    ASSERT_TRUE(LoadKeypointLayoutJson(DataPath("layouts/" + name + ".json"), s, &layout, &error))
        << error;
    EXPECT_EQ(layout.size(), count) << name;
    EXPECT_EQ(layout.name, name);
  }
  KeypointLayout coco;
  ASSERT_TRUE(LoadKeypointLayoutJson(DataPath("layouts/coco17.json"), s, &coco, &error));
  EXPECT_EQ(coco.names[9], "left_wrist");
  EXPECT_EQ(coco.sites[9].bone, s.BoneIndex("hand_l"));
}

TEST(DataFiles, LayoutOffsetsScaleWithTheSubject) {
  Skeleton s, tall;
  std::string error;
  ASSERT_TRUE(LoadSkeletonJson(DataPath("skeleton_default.json"), &s, &error));
  std::vector<Skeleton::Bone> bones = s.bones();
  for (auto& b : bones) b.offset *= 1.2;
  ASSERT_TRUE(Skeleton::Create(bones, &tall, &error));
  KeypointLayout layout;
  ASSERT_TRUE(LoadKeypointLayoutJson(DataPath("layouts/coco17.json"), s, &layout, &error));
  EXPECT_NEAR(layout.ScaledTo(tall).sites[0].offset.norm(), 1.2 * layout.sites[0].offset.norm(),
              1e-9);
}

TEST(DataFiles, ImuSetsAreThePapersSets) {
  Skeleton s;
  std::string error;
  ASSERT_TRUE(LoadSkeletonJson(DataPath("skeleton_default.json"), &s, &error));
  std::vector<ImuSite> imus;
  ASSERT_TRUE(LoadImuSitesJson(DataPath("imus13.json"), s, &imus, &error)) << error;
  EXPECT_EQ(imus.size(), 13u);
  ASSERT_TRUE(LoadImuSitesJson(DataPath("imus6.json"), s, &imus, &error)) << error;
  EXPECT_EQ(imus.size(), 6u);
}

// What a calibrator writes (and publishes in a Calibration message) reads back the same.
TEST(DataFiles, LayoutsAndImuSitesRoundTrip) {
  const testing::Scene scene = testing::MakeScene(2);
  std::vector<Skeleton::Bone> bones = scene.skeleton.bones();
  for (auto& b : bones) b.offset *= 1.1;
  Skeleton tall;
  std::string error;
  ASSERT_TRUE(Skeleton::Create(bones, &tall, &error)) << error;
  KeypointLayout layout = scene.layout.ScaledTo(tall), again;
  layout.sites[4].offset += Eigen::Vector3d(0.01, -0.02, 0.005);
  ASSERT_TRUE(ParseKeypointLayoutJson(KeypointLayoutToJson(tall, layout), tall, &again, &error))
      << error;
  again = again.ScaledTo(tall);  // as the host loads it: no change for this skeleton
  ASSERT_EQ(again.names, layout.names);
  for (int k = 0; k < layout.size(); ++k) {
    EXPECT_EQ(again.sites[k].bone, layout.sites[k].bone);
    EXPECT_LT((again.sites[k].offset - layout.sites[k].offset).norm(), 1e-12) << k;
  }
  std::vector<ImuSite> imus;
  ASSERT_TRUE(ParseImuSitesJson(ImuSitesToJson(tall, scene.imus), tall, &imus, &error)) << error;
  ASSERT_EQ(imus.size(), scene.imus.size());
  for (size_t i = 0; i < imus.size(); ++i) {
    EXPECT_EQ(imus[i].name, scene.imus[i].name);
    EXPECT_EQ(imus[i].bone, scene.imus[i].bone);
    EXPECT_LT((imus[i].mount - scene.imus[i].mount).norm(), 1e-12);
    EXPECT_LT((imus[i].reference - scene.imus[i].reference).norm(), 1e-12);
    EXPECT_LT((imus[i].offset - scene.imus[i].offset).norm(), 1e-12);
  }
}

TEST(DataFiles, MalformedFilesAreRefusedWithAReason) {
  Skeleton s;
  std::string error;
  EXPECT_FALSE(ParseSkeletonJson("{not json", &s, &error));
  EXPECT_EQ(error, "invalid JSON");
  EXPECT_FALSE(ParseSkeletonJson(
      R"({"format": "mocap.skeleton/1", "bones": [{"name": "a", "parent": "zz", "offset": [0,0,0]}]})",
      &s, &error));
  EXPECT_NE(error.find("zz"), std::string::npos);
  EXPECT_FALSE(LoadSkeletonJson("/nonexistent.json", &s, &error));
  ASSERT_TRUE(LoadSkeletonJson(DataPath("skeleton_default.json"), &s, &error));
  KeypointLayout layout;
  EXPECT_FALSE(ParseKeypointLayoutJson(
      R"({"format": "mocap.layout/1", "keypoints": [{"name": "x", "bone": "tail"}]})", s, &layout,
      &error));
  EXPECT_NE(error.find("tail"), std::string::npos);
  Rig rig;
  EXPECT_FALSE(ParseRigJson(
      R"({"format": "mocap.rig/1", "cameras": [{"name": "c", "width": 10, "height": 10, "fx": -1, "fy": 1, "cx": 0, "cy": 0, "rotation": [0,0,0], "translation": [0,0,0]}]})",
      &rig, &error));
  PosePrior prior;
  EXPECT_FALSE(ParsePosePriorJson(
      R"({"format": "mocap.prior/1", "dof": 2, "mean": [0, 0], "basis": [[1, 1]], "sigma": [1]})",
      &prior, &error));
  EXPECT_NE(error.find("orthonormal"), std::string::npos);
}

TEST(DataFiles, PriorRoundTrips) {
  std::mt19937 rng(3);
  const PosePrior p = testing::RandomPrior(60, 23, Eigen::VectorXd::Zero(66), &rng);
  PosePrior q;
  std::string error;
  ASSERT_TRUE(ParsePosePriorJson(PosePriorToJson(p), &q, &error)) << error;
  EXPECT_LT((p.basis - q.basis).norm(), 1e-12);
  EXPECT_EQ(q.rank(), 23);
}

}  // namespace
}  // namespace mocap
