// The session file: every key is read, an unknown one is an error naming it.
#include "session.h"

#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>

#include "options_json.h"
#include "synthetic_scene.h"

namespace mocap {
namespace {

using nlohmann::json;

// A session of the shipped data files with the given extra keys.
std::string WriteSession(const json& extra) {
  json j = {{"format", "mocap.session/1"},
            {"skeleton", testing::DataPath("skeleton_default.json")},
            {"layout", testing::DataPath("layouts/coco17.json")},
            {"imus", testing::DataPath("imus13.json")},
            {"rig", ::testing::TempDir() + "/rig.json"},
            {"inputs", {"tcp://localhost:5600"}},
            {"output", "tcp://*:5700"}};
  std::ofstream(::testing::TempDir() + "/rig.json")
      << RigToJson(testing::MakeScene(2, "coco17").rig);
  j.update(extra);
  const std::string path = ::testing::TempDir() + "/session.json";
  std::ofstream(path) << j.dump();
  return path;
}

TEST(Session, SolverAndSyncKeysAreRead) {
  Session s;
  std::string error;
  ASSERT_TRUE(LoadSession(
      WriteSession(
          {{"solver",
            {{"velocity_gain", 0.5}, {"max_heading_step", 0.2}, {"position", {{"loss", "huber"}}}}},
           {"sync", {{"max_wait_ms", 30}, {"imu_history_ms", 500}, {"imu_only_rate_hz", 100}}},
           {"imus_calibrated", false},
           {"people", 3}}),
      &s, &error))
      << error;
  EXPECT_EQ(s.solver.velocity_gain, 0.5);
  EXPECT_EQ(s.solver.max_heading_step, 0.2);
  EXPECT_EQ(s.solver.position.loss, LossType::kHuber);
  EXPECT_EQ(s.sync.max_wait_ns, 30'000'000);
  EXPECT_EQ(s.sync.imu_history_ns, 500'000'000);
  EXPECT_EQ(s.sync.imu_only_rate_hz, 100);
  EXPECT_FALSE(s.imus_calibrated);
  EXPECT_EQ(s.people, 3);
  EXPECT_EQ(s.rig.cameras.size(), 2u);
  EXPECT_EQ(s.layout.name, "coco17");
}

// A suit file of the 13-IMU set's sensors `which`; its path.
std::string WriteSuit(const std::string& name, const std::vector<json>& sensors) {
  json suit = json::parse(std::ifstream(testing::DataPath("imus13.json")));
  suit["imus"] = sensors;
  const std::string path = ::testing::TempDir() + "/" + name + ".json";
  std::ofstream(path) << suit.dump();
  return path;
}

TEST(Session, SuitsAreSetsOfTheSessionsSensorsEachInOneSuit) {
  const json set = json::parse(std::ifstream(testing::DataPath("imus13.json")))["imus"];
  const std::string a = WriteSuit("suit_a", {set[0], set[1]}), b = WriteSuit("suit_b", {set[2]});
  Session s;
  std::string error;
  ASSERT_TRUE(LoadSession(
      WriteSession({{"people", 2},
                    {"suits",
                     {{{"imus", a}},
                      {{"imus", b}, {"skeleton", testing::DataPath("skeleton_default.json")}}}}}),
      &s, &error))
      << error;
  ASSERT_EQ(s.suits.size(), 2u);
  EXPECT_EQ(s.suits[0].sensors, (std::vector<int>{0, 1}));
  EXPECT_EQ(s.suits[1].sensors, (std::vector<int>{2}));
  EXPECT_EQ(s.suits[1].calibration.imus[0].name, set[2]["name"].get<std::string>());
  json stranger = set[0];
  stranger["name"] = "nosuch";
  const std::vector<std::pair<json, std::string>> cases = {
      {{{"suits", {{{"imus", a}}}}}, "suits are for a session of several people"},
      {{{"people", 2}, {"suits", {{{"imus", a}}, {{"imus", a}}}}}, "is in two suits"},
      {{{"people", 2}, {"suits", {{{"imus", WriteSuit("suit_c", {stranger})}}}}},
       "sensor 'nosuch' is not in the IMU set"},
      {{{"people", 2}, {"suits", {{{"imus", a}, {"colour", "red"}}}}}, "unknown key 'colour'"},
      {{{"people", 2}, {"suits", {{"imus", a}}}}, "suits is a list"},
  };
  for (const auto& [extra, message] : cases) {
    EXPECT_FALSE(LoadSession(WriteSession(extra), &s, &error)) << extra.dump();
    EXPECT_NE(error.find(message), std::string::npos) << error;
  }
}

TEST(Session, AnUnknownKeyIsAnErrorNamingIt) {
  const std::vector<std::pair<json, std::string>> cases = {
      {{{"solver", {{"velocity_gian", 0.5}}}}, "'velocity_gian'"},
      {{{"sync", {{"max_wait", 30}}}}, "'max_wait'"},
      {{{"sync", {{"max_wait_ms", "30"}}}}, "'max_wait_ms' must be a number"},
      {{{"solvr", json::object()}}, "'solvr'"},
      {{{"solver", {{"max_iterations", 0}}}}, "max_iterations = 0 is out of range"},
      {{{"people", 0}}, "people must be a whole number from 1 to 8"},
      {{{"people", 2.5}}, "people must be a whole number from 1 to 8"},
      {{{"people", 9}}, "people must be a whole number from 1 to 8"},
  };
  for (const auto& [extra, message] : cases) {
    Session s;
    std::string error;
    EXPECT_FALSE(LoadSession(WriteSession(extra), &s, &error)) << extra.dump();
    EXPECT_NE(error.find(message), std::string::npos) << error;
  }
}

TEST(Session, TheSyncKeysAreThoseDocumented) {
  const std::vector<std::string> keys = SyncOptionKeys();
  EXPECT_EQ(keys, (std::vector<std::string>{"group_tolerance_ms", "max_wait_ms", "stale_after_ms",
                                            "imu_max_gap_ms", "imu_max_hold_ms", "imu_history_ms",
                                            "imu_only_rate_hz"}));
}

// A data file of the shipped set with `edit` applied, written to the test's folder.
std::string Edited(const std::string& data_file, const std::string& out_name,
                   const std::function<void(json*)>& edit) {
  std::ifstream in(testing::DataPath(data_file));
  json j = json::parse(in);
  edit(&j);
  const std::string path = ::testing::TempDir() + "/" + out_name;
  std::ofstream(path) << j.dump();
  return path;
}

TEST(Session, RepeatedNamesAndAnEmptyLayoutAreRefusedAtLoad) {
  Rig twins = testing::MakeScene(2, "coco17").rig;
  twins.cameras[1].name = twins.cameras[0].name;
  std::ofstream(::testing::TempDir() + "/twins.json") << RigToJson(twins);
  const std::string imus = Edited("imus13.json", "imus_twice.json", [](json* j) {
    (*j)["imus"][1]["name"] = (*j)["imus"][0]["name"];
  });
  const std::string layout = Edited("layouts/coco17.json", "empty_layout.json",
                                    [](json* j) { (*j)["keypoints"] = json::array(); });
  const std::vector<std::pair<json, std::string>> cases = {
      {{{"rig", ::testing::TempDir() + "/twins.json"}},
       "rig: two cameras are named '" + twins.cameras[0].name + "'"},
      {{{"imus", imus}}, "imus: two IMUs are named 'head'"},
      {{{"layout", layout}}, "no keypoints"},
  };
  for (const auto& [extra, message] : cases) {
    Session s;
    std::string error;
    EXPECT_FALSE(LoadSession(WriteSession(extra), &s, &error)) << extra.dump();
    EXPECT_NE(error.find(message), std::string::npos) << error;
    EXPECT_NE(error.find("session.json: "), std::string::npos) << error;
  }
}

// A session naming a device or a huge file is refused before it is read: reading /dev/zero
// would never end, and a huge file would be held in memory whole.
TEST(Session, DevicesAndHugeFilesAreRefused) {
  Session s;
  std::string error;
  EXPECT_FALSE(LoadSession(WriteSession({{"skeleton", "/dev/zero"}}), &s, &error));
  EXPECT_NE(error.find("not a regular file"), std::string::npos) << error;
  const std::string huge = ::testing::TempDir() + "/huge.json";
  std::ofstream(huge) << std::string(16u << 20, ' ') << "{}";
  EXPECT_FALSE(LoadSession(WriteSession({{"prior", huge}}), &s, &error));
  EXPECT_NE(error.find("larger than 16 MiB"), std::string::npos) << error;
  EXPECT_FALSE(LoadSession("/dev/zero", &s, &error));
}

// A prior's dof is checked against its mean before anything is allocated by it (a dof of
// 2e9 asked for 16 GB).
TEST(Session, APriorsDofIsCappedBeforeItIsAllocated) {
  const std::string prior = ::testing::TempDir() + "/prior.json";
  std::ofstream(prior) << R"({"format": "mocap.prior/1", "dof": 2000000000, "mean": [0],
                             "basis": [[1]], "sigma": [1]})";
  Session s;
  std::string error;
  EXPECT_FALSE(LoadSession(WriteSession({{"prior", prior}}), &s, &error));
  EXPECT_NE(error.find("dof <= 1024"), std::string::npos) << error;
}

}  // namespace
}  // namespace mocap
