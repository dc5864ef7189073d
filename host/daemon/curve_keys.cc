#include "curve_keys.h"

#include <sys/stat.h>
#include <zmq.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace mocap {
namespace {

constexpr size_t kKeyChars = 40;  // Z85 of 32 bytes

std::string Trimmed(const std::string& s) {
  const size_t first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t\r\n") - first + 1);
}

// "host_key": the secret key file, relative to base.
bool ReadHostKey(const nlohmann::json& j, const std::string& base, CurveKeys* out,
                 std::string* error) {
  if (!j.contains("host_key") || !j.at("host_key").is_string())
    return *error = "curve: host_key (the host's secret key file) is missing", false;
  const std::string path = (std::filesystem::path(base) / j.at("host_key").get<std::string>());
  return ReadSecretKeyFile(path, &out->host_public, &out->host_secret, error);
}

bool ReadInputKeys(const nlohmann::json& j, const std::vector<std::string>& inputs, CurveKeys* out,
                   std::string* error) {
  if (!j.contains("inputs") || !j.at("inputs").is_object())
    return *error = "curve: inputs (endpoint -> public key) is missing", false;
  for (const auto& [endpoint, key] : j.at("inputs").items()) {
    if (std::find(inputs.begin(), inputs.end(), endpoint) == inputs.end())
      return *error = "curve: key for '" + endpoint + "', which is not an input", false;
    if (!key.is_string() || !IsCurveKey(key.get<std::string>()))
      return *error = "curve: the key of '" + endpoint +
                      "' is not a public key (40 characters of Z85, as `mocap keys` writes)",
             false;
    out->input_keys[endpoint] = key.get<std::string>();
  }
  for (const std::string& endpoint : inputs) {
    if (!out->input_keys.count(endpoint))
      return *error = "curve: no key for input '" + endpoint + "'", false;
  }
  return true;
}

bool ReadSubscribers(const nlohmann::json& j, CurveKeys* out, std::string* error) {
  if (!j.contains("subscribers")) return true;
  if (!j.at("subscribers").is_array())
    return *error = "curve: subscribers is a list of public keys", false;
  for (const auto& key : j.at("subscribers")) {
    if (!key.is_string() || !IsCurveKey(key.get<std::string>()))
      return *error = "curve: subscriber " + key.dump() + " is not a public key", false;
    out->subscribers.push_back(key.get<std::string>());
  }
  out->restrict_subscribers = true;
  return true;
}

}  // namespace

bool IsCurveKey(const std::string& text) {
  if (text.size() != kKeyChars) return false;
  uint8_t bytes[32];
  return zmq_z85_decode(bytes, text.c_str()) != nullptr;
}

bool ReadSecretKeyFile(const std::string& path, std::string* public_key, std::string* secret_key,
                       std::string* error) {
  struct stat st;
  if (stat(path.c_str(), &st) != 0) return *error = "cannot open secret key " + path, false;
  if (st.st_mode & (S_IRWXG | S_IRWXO)) {
    std::ostringstream mode;
    mode << std::oct << (st.st_mode & 0777);
    return *error = "secret key " + path + " is readable by others (mode 0" + mode.str() +
                    "): chmod 600 it",
           false;
  }
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  const std::string secret = Trimmed(text.str());
  char derived[kKeyChars + 1];
  if (!in || !IsCurveKey(secret) || zmq_curve_public(derived, secret.c_str()) != 0)
    return *error = path + " is not a secret key (40 characters of Z85, as `mocap keys` writes)",
           false;
  *secret_key = secret;
  *public_key = derived;
  return true;
}

bool ReadCurveKeys(const nlohmann::json& j, const std::string& base,
                   const std::vector<std::string>& inputs, CurveKeys* out, std::string* error) {
  if (!j.is_object()) return *error = "curve is an object", false;
  for (const auto& [key, value] : j.items()) {
    if (key != "host_key" && key != "inputs" && key != "subscribers")
      return *error = "unknown curve key '" + key + "'", false;
  }
  CurveKeys keys;
  if (!ReadHostKey(j, base, &keys, error) || !ReadInputKeys(j, inputs, &keys, error) ||
      !ReadSubscribers(j, &keys, error))
    return false;
  *out = std::move(keys);
  return true;
}

bool IsLocalEndpoint(const std::string& endpoint) {
  if (endpoint.rfind("ipc://", 0) == 0 || endpoint.rfind("inproc://", 0) == 0) return true;
  if (endpoint.rfind("tcp://", 0) != 0) return false;
  const std::string host = endpoint.substr(6, endpoint.rfind(':') - 6);
  const bool dotted = host.find_first_not_of("0123456789.") == std::string::npos;
  return (host.rfind("127.", 0) == 0 && dotted) || host == "localhost" || host == "[::1]";
}

}  // namespace mocap
