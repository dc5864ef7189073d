// The session's "solver" and "sync" objects: every field of SolverOptions (of SyncOptions, but
// the memory bound) is read (none is dropped), an unknown key or a value of the wrong type is
// refused with its name.
#include "options_json.h"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <set>

namespace mocap {
namespace {

using nlohmann::json;

// A value of each field's type that differs from the default and stays in range.
void Change(bool* v) { *v = !*v; }
void Change(int* v) { *v += 3; }
void Change(double* v) { *v = std::isnan(*v) ? 0.05 : *v * 0.5 + 0.01; }  // NaN: unknown
void Change(LossType* v) { *v = *v == LossType::kHuber ? LossType::kCauchy : LossType::kHuber; }
void Change(Eigen::Vector3d* v) { *v += Eigen::Vector3d(0.1, -0.2, 0.3); }
void Change(TermOptions* t) {
  TermOptions::VisitFields([&](const char*, auto member) { Change(&(t->*member)); });
}

template <typename T>
bool Equal(const T& a, const T& b) {
  if constexpr (std::is_same_v<T, TermOptions>) {
    bool equal = true;
    TermOptions::VisitFields([&](const char*, auto m) { equal = equal && Equal(a.*m, b.*m); });
    return equal;
  } else {
    return a == b;
  }
}

TEST(OptionsJson, EveryFieldIsReadBack) {
  const SolverOptions defaults;
  SolverOptions changed;
  SolverOptions::VisitFields([&](const char*, auto member) { Change(&(changed.*member)); });
  ASSERT_TRUE(changed.IsValid(nullptr));
  SolverOptions read;
  std::string error;
  ASSERT_TRUE(ParseSolverOptionsJson(SolverOptionsToJson(changed), &read, &error)) << error;
  SolverOptions::VisitFields([&](const char* name, auto member) {
    EXPECT_FALSE(Equal(defaults.*member, changed.*member)) << name << " was not changed";
    EXPECT_TRUE(Equal(read.*member, changed.*member)) << name << " was not read";
  });
}

TEST(OptionsJson, KeysLeftOutKeepTheirValues) {
  SolverOptions o;
  std::string error;
  ASSERT_TRUE(ReadSolverOptions(json::parse(R"({"velocity_gain": 0.5, "position": {"loss":
      "huber"}, "accel_at_rest": [0, 0, 9.81], "max_iterations": 4})"),
                                &o, &error))
      << error;
  EXPECT_EQ(o.velocity_gain, 0.5);
  EXPECT_EQ(o.position.loss, LossType::kHuber);
  EXPECT_EQ(o.position.weight, SolverOptions().position.weight);
  EXPECT_EQ(o.accel_at_rest, Eigen::Vector3d(0, 0, 9.81));
  EXPECT_EQ(o.max_iterations, 4);
  EXPECT_EQ(o.max_keypoint_cost, SolverOptions().max_keypoint_cost);
}

// The floor's height unknown (NaN, the default) is null in JSON, which has no NaN.
TEST(OptionsJson, AnUnknownFloorIsNull) {
  EXPECT_TRUE(json::parse(SolverOptionsToJson(SolverOptions()))["floor_height"].is_null());
  SolverOptions o;
  std::string error;
  ASSERT_TRUE(ParseSolverOptionsJson(R"({"floor_height": 0.04})", &o, &error)) << error;
  EXPECT_EQ(o.floor_height, 0.04);
  ASSERT_TRUE(ParseSolverOptionsJson(R"({"floor_height": null})", &o, &error)) << error;
  EXPECT_TRUE(std::isnan(o.floor_height));
}

TEST(OptionsJson, AnUnknownKeyOrAWrongValueIsRefusedByName) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"({"velocity_gian": 0.5})", "unknown key 'velocity_gian'"},
      {R"({"position": {"wieght": 1}})", "unknown key 'position.wieght'"},
      {R"({"max_iterations": 2.5})", "'max_iterations' must be an integer"},
      {R"({"predict_motion": 1})", "'predict_motion' must be true or false"},
      {R"({"position": {"loss": "cauchi"}})", "'position.loss' must be"},
      {R"({"accel_at_rest": [0, 9.8]})", "'accel_at_rest' must be [x, y, z]"},
      {R"({"orientation": 3})", "'orientation' must be an object"},
      {R"({"velocity_gain": 0})", "velocity_gain = 0 is out of range"},
      {R"({"velocity_gain": null})", "velocity_gain = nan is out of range"},
      {R"({"floor_height": "low"})", "'floor_height' must be a number (or null: unknown)"},
      {R"([1])", "must be an object"},
  };
  for (const auto& [text, message] : cases) {
    SolverOptions o;
    std::string error;
    EXPECT_FALSE(ParseSolverOptionsJson(text, &o, &error)) << text;
    EXPECT_NE(error.find(message), std::string::npos) << text << ": " << error;
  }
}

TEST(OptionsJson, TheKeysAreTheFieldsWithTermsAsTermDotField) {
  const std::vector<std::string> keys = SolverOptionKeys();
  const std::set<std::string> unique(keys.begin(), keys.end());
  EXPECT_EQ(unique.size(), keys.size());
  EXPECT_EQ(keys.size(), 7 * 4 + 25u);  // seven terms of four fields, twenty-five others
  for (const char* key : {"position.loss_scale", "pca_deviation.enabled", "velocity_gain",
                          "motion.weight", "motion_velocity_gain", "ground.weight", "floor_height",
                          "prediction_slack", "accel_at_rest", "max_initial_iterations"})
    EXPECT_TRUE(unique.count(key)) << key;
  const json written = json::parse(SolverOptionsToJson(SolverOptions()));
  for (const std::string& key : keys) {
    const size_t dot = key.find('.');
    EXPECT_TRUE(dot == std::string::npos
                    ? written.contains(key)
                    : written.at(key.substr(0, dot)).contains(key.substr(dot + 1)))
        << key;
  }
}

// Every sync key sets its field (times given in ms), and only that field.
TEST(OptionsJson, EverySyncKeySetsItsField) {
  const std::vector<std::string> keys = SyncOptionKeys();
  ASSERT_EQ(keys.size(), 7u);  // every field but max_pending_frames
  for (const std::string& key : keys) {
    SyncOptions o;
    std::string error;
    ASSERT_TRUE(ReadSyncOptions(json{{key, 500}}, &o, &error)) << key << ": " << error;
    int changed = 0;
    SyncOptions::VisitFields([&](const char* name, auto member) {
      if (o.*member == SyncOptions().*member) return;
      changed++;
      const bool time = key.size() > 3 && key.compare(key.size() - 3, 3, "_ms") == 0;
      EXPECT_EQ(static_cast<double>(o.*member), time ? 5e8 : 500.0) << name;
    });
    EXPECT_EQ(changed, 1) << key;
  }
}

TEST(OptionsJson, AnUnknownSyncKeyOrAWrongValueIsRefusedByName) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"({"max_wait": 30})", "unknown sync option 'max_wait'"},
      {R"({"max_wait_ns": 30})", "unknown sync option 'max_wait_ns'"},
      {R"({"max_pending_frames": 30})", "unknown sync option 'max_pending_frames'"},
      {R"({"": 30})", "unknown sync option ''"},
      {R"({"max_wait_ms": "30"})", "sync option 'max_wait_ms' must be a number"},
      {R"({"max_wait_ms": true})", "sync option 'max_wait_ms' must be a number"},
      {R"({"imu_max_gap_ms": -1})", "sync options out of range"},
      {R"([1])", "sync must be an object"},
      {R"({"max_wait_ms": )", "invalid JSON"},
  };
  for (const auto& [text, message] : cases) {
    SyncOptions o;
    std::string error;
    EXPECT_FALSE(ParseSyncOptionsJson(text, &o, &error)) << text;
    EXPECT_NE(error.find(message), std::string::npos) << text << ": " << error;
  }
}

}  // namespace
}  // namespace mocap
