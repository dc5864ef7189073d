// Small helpers for the JSON files of the host library (nlohmann::json).
#ifndef MOCAP_SRC_JSON_UTIL_H_
#define MOCAP_SRC_JSON_UTIL_H_

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

namespace mocap {
namespace internal {

// The largest file the host reads (session, skeleton, rig, layout, IMU set, prior: the
// shipped prior, the largest, is 25 kB): a path naming a device or a huge file is refused
// before it is read (docs/reliability.md, "Fuzzing").
inline constexpr std::uintmax_t kMaxTextFileBytes = 16u << 20;

inline bool ReadTextFile(const std::string& path, std::string* text, std::string* error) {
  std::error_code ec;
  const bool regular = std::filesystem::is_regular_file(path, ec);
  const std::uintmax_t size = regular ? std::filesystem::file_size(path, ec) : 0;
  if (regular && !ec && size > kMaxTextFileBytes) {
    *error = path + " is larger than " + std::to_string(kMaxTextFileBytes >> 20) + " MiB";
    return false;
  }
  std::ifstream in(path);
  if (!in || !regular || ec) {
    *error = "cannot open " + path + (in && !regular ? " (not a regular file)" : "");
    return false;
  }
  std::stringstream ss;
  ss << in.rdbuf();
  *text = ss.str();
  return true;
}

// Reads path and hands its text to parse(text); a failure's *error is prefixed with the path.
template <typename Parse>
bool LoadFile(const std::string& path, std::string* error, Parse parse) {
  std::string text;
  if (!ReadTextFile(path, &text, error)) return false;
  if (!parse(text)) {
    *error = path + ": " + *error;
    return false;
  }
  return true;
}

// Parses text; on failure sets *error and returns false.
inline bool ParseJson(const std::string& text, nlohmann::json* out, std::string* error) {
  *out = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (out->is_discarded()) {
    *error = "invalid JSON";
    return false;
  }
  return true;
}

// Runs parse(), a reader of JSON that checks each value's type before it reads it; a lookup
// that still meets a value of another type (nlohmann throws then, e.g. value() of a number
// as a string) is an error with its message, so the Parse*Json functions never throw.
template <typename Parse>
bool Guarded(std::string* error, Parse parse) {
  try {
    return parse();
  } catch (const nlohmann::json::exception& e) {
    *error = std::string("malformed field: ") + e.what();
    return false;
  }
}

// Reads a JSON array of n finite numbers.
inline bool ReadVector(const nlohmann::json& j, int n, double* out) {
  if (!j.is_array() || static_cast<int>(j.size()) != n) return false;
  for (int i = 0; i < n; ++i) {
    if (!j[i].is_number()) return false;
    out[i] = j[i].get<double>();
    if (!std::isfinite(out[i])) return false;
  }
  return true;
}

inline bool ReadVector3(const nlohmann::json& j, Eigen::Vector3d* v) {
  return ReadVector(j, 3, v->data());
}

}  // namespace internal
}  // namespace mocap

#endif  // MOCAP_SRC_JSON_UTIL_H_
