#include "session.h"

#include <filesystem>
#include <nlohmann/json.hpp>

#include "../src/json_util.h"

namespace mocap {
namespace {

using nlohmann::json;

bool ReadSync(const json& j, SyncOptions* sync, std::string* error) {
  const auto ns = [&](const char* key, int64_t* field) {
    if (j.contains(key)) *field = static_cast<int64_t>(j.at(key).get<double>() * 1e6);
  };
  ns("group_tolerance_ms", &sync->group_tolerance_ns);
  ns("max_wait_ms", &sync->max_wait_ns);
  ns("stale_after_ms", &sync->stale_after_ns);
  ns("imu_max_gap_ms", &sync->imu_max_gap_ns);
  ns("imu_max_hold_ms", &sync->imu_max_hold_ns);
  if (j.contains("imu_only_rate_hz"))
    sync->imu_only_rate_hz = j.at("imu_only_rate_hz").get<double>();
  return sync->IsValid(error);
}

bool ReadSolver(const json& j, SolverOptions* options, std::string* error) {
  for (const auto& [key, value] : j.items()) {
    if (key == "function_tolerance")
      options->function_tolerance = value.get<double>();
    else if (key == "max_iterations")
      options->max_iterations = value.get<int>();
    else if (key == "predict_motion")
      options->predict_motion = value.get<bool>();
    else if (key == "velocity_gain")
      options->velocity_gain = value.get<double>();
    else if (key == "max_keypoint_cost")
      options->max_keypoint_cost = value.get<double>();
    else if (key == "heading_time_constant")
      options->heading_time_constant = value.get<double>();
    else if (key == "heading_baseline_s")
      options->heading_baseline_s = value.get<double>();
    else
      return *error = "unknown solver option '" + key + "'", false;
  }
  return options->IsValid(error);
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
    if (j.contains("solver") && !ReadSolver(j.at("solver"), &s.solver, error))
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
