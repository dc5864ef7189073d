#include "session.h"

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "../src/json_util.h"
#include "options_json.h"

namespace mocap {
namespace {

using nlohmann::json;

std::string Join(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

// The sync object's keys: the synchroniser's times in milliseconds, its IMU-only rate in Hz.
constexpr std::pair<const char*, int64_t SyncOptions::*> kSyncMs[] = {
    {"group_tolerance_ms", &SyncOptions::group_tolerance_ns},
    {"max_wait_ms", &SyncOptions::max_wait_ns},
    {"stale_after_ms", &SyncOptions::stale_after_ns},
    {"imu_max_gap_ms", &SyncOptions::imu_max_gap_ns},
    {"imu_max_hold_ms", &SyncOptions::imu_max_hold_ns},
    {"imu_history_ms", &SyncOptions::imu_history_ns}};
constexpr const char* kSyncRate = "imu_only_rate_hz";

// The keys of the session object itself.
constexpr const char* kSessionKeys[] = {"format",         "skeleton", "rig",    "layout", "imus",
                                        "prior",          "inputs",   "output", "sync",   "solver",
                                        "imus_calibrated"};

bool ReadSync(const json& j, SyncOptions* sync, std::string* error) {
  if (!j.is_object()) return *error = "sync must be an object", false;
  for (const auto& [key, value] : j.items()) {
    double* rate = key == kSyncRate ? &sync->imu_only_rate_hz : nullptr;
    int64_t SyncOptions::*ns = nullptr;
    for (const auto& [name, member] : kSyncMs) ns = key == name ? member : ns;
    if (!rate && !ns)
      return *error = "unknown sync option '" + key + "' (known: " + Join(SyncOptionKeys()) + ")",
             false;
    if (!value.is_number()) return *error = "sync option '" + key + "' must be a number", false;
    if (rate) *rate = value.get<double>();
    if (ns) sync->*ns = static_cast<int64_t>(value.get<double>() * 1e6);
  }
  return sync->IsValid(error);
}

bool CheckSessionKeys(const json& j, std::string* error) {
  if (!j.is_object()) return *error = "a session is a JSON object", false;
  for (const auto& [key, value] : j.items()) {
    if (std::find(std::begin(kSessionKeys), std::end(kSessionKeys), key) == std::end(kSessionKeys))
      return *error = "unknown session key '" + key + "'", false;
  }
  return true;
}

}  // namespace

std::vector<std::string> SyncOptionKeys() {
  std::vector<std::string> keys;
  for (const auto& [name, member] : kSyncMs) keys.push_back(name);
  keys.push_back(kSyncRate);
  return keys;
}

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
    if (j.contains("sync") && !ReadSync(j.at("sync"), &s.sync, error))
      throw std::runtime_error(*error);
    if (j.contains("solver") && !ReadSolverOptions(j.at("solver"), &s.solver, error))
      throw std::runtime_error(*error);
    s.imus_calibrated = j.value("imus_calibrated", true);
    *out = std::move(s);
    return true;
  } catch (const std::exception& e) {
    *error = path + ": " + e.what();
    return false;
  }
}

}  // namespace mocap
