#include "session.h"

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "../src/json_util.h"
#include "options_json.h"

namespace mocap {
namespace {

using nlohmann::json;

// The keys of the session object itself.
constexpr const char* kSessionKeys[] = {"format",          "skeleton", "rig",    "layout", "imus",
                                        "prior",           "inputs",   "output", "sync",   "solver",
                                        "imus_calibrated", "curve",    "people", "suits"};

bool CheckSessionKeys(const json& j, std::string* error) {
  if (!j.is_object()) return *error = "a session is a JSON object", false;
  for (const auto& [key, value] : j.items()) {
    if (std::find(std::begin(kSessionKeys), std::end(kSessionKeys), key) == std::end(kSessionKeys))
      return *error = "unknown session key '" + key + "'", false;
  }
  return true;
}

// Streams are told apart by name on the wire (camera ids, sensor ids) and keypoints by index:
// a repeated name or an empty layout would have its streams dropped while running.
void CheckNames(const Session& s) {
  const auto repeated = [](const std::vector<std::string>& names) -> std::string {
    for (size_t i = 0; i < names.size(); ++i)
      if (std::find(names.begin(), names.begin() + i, names[i]) != names.begin() + i)
        return names[i];
    return "";
  };
  std::vector<std::string> cameras, sensors;
  for (const Camera& c : s.rig.cameras) cameras.push_back(c.name);
  for (const ImuSite& imu : s.imus) sensors.push_back(imu.name);
  if (const std::string name = repeated(cameras); !name.empty())
    throw std::runtime_error("rig: two cameras are named '" + name +
                             "' (camera ids on the wire must be unique)");
  if (const std::string name = repeated(sensors); !name.empty())
    throw std::runtime_error("imus: two IMUs are named '" + name +
                             "' (sensor ids on the wire must be unique)");
  if (s.layout.size() == 0) throw std::runtime_error("layout: no keypoints");
}

// "people" and "suits" (session.h), once the skeleton, layout and IMU set are read.
void ReadPeople(const json& j, const std::filesystem::path& base, Session* s) {
  if (j.contains("people")) {
    const json& people = j.at("people");
    if (!people.is_number_integer() || people.get<int>() < 1 || people.get<int>() > kMaxPeople)
      throw std::runtime_error("people must be a whole number from 1 to " +
                               std::to_string(kMaxPeople));
    s->people = people.get<int>();
  }
  if (!j.contains("suits")) return;
  if (s->people < 2) throw std::runtime_error("suits are for a session of several people");
  if (!j.at("suits").is_array()) throw std::runtime_error("suits is a list");
  std::vector<int> worn(s->imus.size(), -1);  // per session IMU: the suit it is in
  for (const json& entry : j.at("suits")) {
    const std::string where = "suit " + std::to_string(s->suits.size());
    if (!entry.is_object() || !entry.contains("imus"))
      throw std::runtime_error(where + ": an object with \"imus\" (and \"skeleton\")");
    for (const auto& [key, value] : entry.items())
      if (key != "imus" && key != "skeleton")
        throw std::runtime_error(where + ": unknown key '" + key + "'");
    std::string error;
    Suit suit;
    suit.calibration.skeleton = s->skeleton;
    if (entry.contains("skeleton") &&
        !LoadSkeletonJson((base / entry.at("skeleton").get<std::string>()).string(),
                          &suit.calibration.skeleton, &error))
      throw std::runtime_error(where + ": " + error);
    if (!LoadImuSitesJson((base / entry.at("imus").get<std::string>()).string(),
                          suit.calibration.skeleton, &suit.calibration.imus, &error))
      throw std::runtime_error(where + ": " + error);
    suit.calibration.layout = s->layout.ScaledTo(suit.calibration.skeleton);
    for (const ImuSite& site : suit.calibration.imus) {
      const auto it = std::find_if(s->imus.begin(), s->imus.end(),
                                   [&](const ImuSite& i) { return i.name == site.name; });
      if (it == s->imus.end())
        throw std::runtime_error(where + ": sensor '" + site.name + "' is not in the IMU set");
      int& in = worn[it - s->imus.begin()];
      if (in >= 0) throw std::runtime_error(where + ": sensor '" + site.name + "' is in two suits");
      in = static_cast<int>(s->suits.size());
      suit.sensors.push_back(static_cast<int>(it - s->imus.begin()));
    }
    s->suits.push_back(std::move(suit));
  }
}

}  // namespace

bool LoadSession(const std::string& path, Session* out, std::string* error) {
  std::string text;
  json j;
  if (!internal::ReadTextFile(path, &text, error) || !internal::ParseJson(text, &j, error)) {
    *error = path + ": " + *error;
    return false;
  }
  const std::filesystem::path base = std::filesystem::path(path).parent_path();
  const auto file = [&](const char* key) { return (base / j.at(key).get<std::string>()).string(); };
  try {
    if (!CheckSessionKeys(j, error)) throw std::runtime_error(*error);
    if (j.value("format", "") != "mocap.session/1")
      throw std::runtime_error("format is not mocap.session/1");
    Session s;
    if (!LoadSkeletonJson(file("skeleton"), &s.skeleton, error) ||
        !LoadRigJson(file("rig"), &s.rig, error) ||
        !LoadImuSitesJson(file("imus"), s.skeleton, &s.imus, error)) {
      throw std::runtime_error(*error);
    }
    KeypointLayout layout;
    if (!LoadKeypointLayoutJson(file("layout"), s.skeleton, &layout, error))
      throw std::runtime_error(*error);
    s.layout = layout.ScaledTo(s.skeleton);
    if (j.contains("prior") && !j.at("prior").is_null()) {
      PosePrior prior;
      if (!LoadPosePriorJson(file("prior"), &prior, error)) throw std::runtime_error(*error);
      s.prior = std::move(prior);
    }
    s.inputs = j.at("inputs").get<std::vector<std::string>>();
    s.output = j.at("output").get<std::string>();
    if (s.inputs.empty()) throw std::runtime_error("no inputs");
    if (j.contains("sync") && !ReadSyncOptions(j.at("sync"), &s.sync, error))
      throw std::runtime_error(*error);
    if (j.contains("solver") && !ReadSolverOptions(j.at("solver"), &s.solver, error))
      throw std::runtime_error(*error);
    s.imus_calibrated = j.value("imus_calibrated", true);
    ReadPeople(j, base, &s);
    if (j.contains("curve")) {
      CurveKeys keys;
      if (!ReadCurveKeys(j.at("curve"), base.string(), s.inputs, &keys, error))
        throw std::runtime_error(*error);
      s.curve = std::move(keys);
    }
    CheckNames(s);
    *out = std::move(s);
    return true;
  } catch (const std::exception& e) {
    *error = path + ": " + e.what();
    return false;
  }
}

}  // namespace mocap
