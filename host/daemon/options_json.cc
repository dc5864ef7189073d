#include "options_json.h"

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <type_traits>

namespace mocap {
namespace {

using nlohmann::json;

// Whether T names its fields (a struct of options, read as an object of its fields).
struct IgnoreField {
  template <typename Member>
  void operator()(const char*, Member) const {}
};
template <typename T, typename = void>
struct HasFields : std::false_type {};
template <typename T>
struct HasFields<T, std::void_t<decltype(T::VisitFields(IgnoreField{}))>> : std::true_type {};

constexpr const char* kLossNames[] = {"trivial", "cauchy", "huber"};  // LossType's order

// One value of a leaf field: false when j has the wrong type. Expected() names the type.
bool ReadValue(const json& j, bool* v) { return j.is_boolean() && (*v = j.get<bool>(), true); }
// null is NaN, "unknown" (JSON has no NaN; nlohmann writes it as null): floor_height's way of
// saying there is no floor estimate. Every other field's range check refuses NaN by name.
bool ReadValue(const json& j, double* v) {
  if (j.is_null()) return *v = std::numeric_limits<double>::quiet_NaN(), true;
  return j.is_number() && (*v = j.get<double>(), true);
}
bool ReadValue(const json& j, int* v) {
  if (!j.is_number()) return false;
  const double d = j.get<double>();
  if (d != std::floor(d) || std::abs(d) > 1e9) return false;
  *v = static_cast<int>(d);
  return true;
}
bool ReadValue(const json& j, LossType* v) {
  for (int i = 0; i < 3; ++i) {
    if (j.is_string() && j.get<std::string>() == kLossNames[i])
      return *v = static_cast<LossType>(i), true;
  }
  return false;
}
bool ReadValue(const json& j, Eigen::Vector3d* v) {
  if (!j.is_array() || j.size() != 3) return false;
  for (int i = 0; i < 3; ++i) {
    if (!j[i].is_number()) return false;
    (*v)(i) = j[i].get<double>();
  }
  return true;
}
const char* Expected(const bool*) { return "true or false"; }
const char* Expected(const double*) { return "a number (or null: unknown)"; }
const char* Expected(const int*) { return "an integer"; }
const char* Expected(const LossType*) { return "\"trivial\", \"cauchy\" or \"huber\""; }
const char* Expected(const Eigen::Vector3d*) { return "[x, y, z]"; }

json ValueToJson(bool v) { return v; }
json ValueToJson(double v) { return std::isnan(v) ? json() : json(v); }
json ValueToJson(int v) { return v; }
json ValueToJson(LossType v) { return kLossNames[static_cast<int>(v)]; }
json ValueToJson(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

template <typename T>
void AddKeys(const std::string& prefix, std::vector<std::string>* keys) {
  T::VisitFields([&](const char* name, auto member) {
    using Field = std::remove_reference_t<decltype(std::declval<T>().*member)>;
    if constexpr (HasFields<Field>::value)
      AddKeys<Field>(prefix + name + ".", keys);
    else
      keys->push_back(prefix + name);
  });
}

template <typename T>
bool ReadFields(const json& j, const std::string& prefix, T* options, std::string* error);

template <typename Field>
bool ReadField(const json& j, const std::string& key, Field* value, std::string* error) {
  if constexpr (HasFields<Field>::value) {
    return ReadFields(j, key + ".", value, error);
  } else {
    if (ReadValue(j, value)) return true;
    *error = "'" + key + "' must be " + Expected(value) + ", not " + j.dump();
    return false;
  }
}

template <typename T>
bool ReadFields(const json& j, const std::string& prefix, T* options, std::string* error) {
  if (!j.is_object()) {
    *error = prefix.empty() ? "must be an object"
                            : "'" + prefix.substr(0, prefix.size() - 1) + "' must be an object";
    return false;
  }
  for (const auto& [key, value] : j.items()) {
    bool known = false, ok = true;
    T::VisitFields([&, key = key, &value = value](const char* name, auto member) {
      if (known || key != name) return;
      known = true;
      ok = ReadField(value, prefix + key, &(options->*member), error);
    });
    if (!ok) return false;
    if (!known) {
      std::string names;
      T::VisitFields([&](const char* name, auto) {
        names += (names.empty() ? "" : ", ") + std::string(name);
      });
      *error = "unknown key '" + prefix + key + "' (known: " + names + ")";
      return false;
    }
  }
  return true;
}

// The "sync" key of a SyncOptions field (a time in milliseconds), empty for a field the
// session does not set.
std::string SyncKey(const std::string& field) {
  if (field == "max_pending_frames") return "";
  const size_t n = field.size();
  return n > 3 && field.compare(n - 3, 3, "_ns") == 0 ? field.substr(0, n - 3) + "_ms" : field;
}

// One "sync" number into its field: a time from milliseconds to nanoseconds.
template <typename Field>
void ReadSyncValue(const json& value, Field* field) {
  if constexpr (std::is_same_v<Field, int64_t>)
    *field = static_cast<int64_t>(value.get<double>() * 1e6);
  else
    *field = static_cast<Field>(value.get<double>());
}

template <typename T>
json FieldsToJson(const T& options) {
  json j = json::object();
  T::VisitFields([&](const char* name, auto member) {
    using Field = std::remove_reference_t<decltype(options.*member)>;
    if constexpr (HasFields<std::remove_const_t<Field>>::value)
      j[name] = FieldsToJson(options.*member);
    else
      j[name] = ValueToJson(options.*member);
  });
  return j;
}

}  // namespace

bool ReadSolverOptions(const json& j, SolverOptions* options, std::string* error) {
  std::string why;
  if (!ReadFields(j, "", options, &why) || !options->IsValid(&why)) {
    *error = "solver options: " + why;
    return false;
  }
  return true;
}

bool ParseSolverOptionsJson(const std::string& text, SolverOptions* options, std::string* error) {
  const json j = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) return *error = "solver options: invalid JSON", false;
  return ReadSolverOptions(j, options, error);
}

std::string SolverOptionsToJson(const SolverOptions& options) {
  return FieldsToJson(options).dump(1);
}

std::vector<std::string> SolverOptionKeys() {
  std::vector<std::string> keys;
  AddKeys<SolverOptions>("", &keys);
  return keys;
}

bool ReadSyncOptions(const json& j, SyncOptions* sync, std::string* error) {
  if (!j.is_object()) return *error = "sync must be an object", false;
  for (const auto& [key, value] : j.items()) {
    bool known = false;
    SyncOptions::VisitFields([&, key = key, &value = value](const char* name, auto member) {
      const std::string k = SyncKey(name);
      if (known || k.empty() || k != key) return;
      known = true;
      if (value.is_number()) ReadSyncValue(value, &(sync->*member));
    });
    if (!known) {
      std::string names;
      for (const std::string& n : SyncOptionKeys()) names += (names.empty() ? "" : ", ") + n;
      *error = "unknown sync option '" + key + "' (known: " + names + ")";
      return false;
    }
    if (!value.is_number()) return *error = "sync option '" + key + "' must be a number", false;
  }
  return sync->IsValid(error);
}

bool ParseSyncOptionsJson(const std::string& text, SyncOptions* sync, std::string* error) {
  const json j = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) return *error = "sync options: invalid JSON", false;
  return ReadSyncOptions(j, sync, error);
}

std::vector<std::string> SyncOptionKeys() {
  std::vector<std::string> keys;
  SyncOptions::VisitFields([&](const char* name, auto) {
    if (const std::string k = SyncKey(name); !k.empty()) keys.push_back(k);
  });
  return keys;
}

}  // namespace mocap
