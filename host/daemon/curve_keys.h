// The session's CURVE keys (ZeroMQ's CurveZMQ: every stream authenticated and encrypted).
//   "curve": {"host_key": "keys/host.key",                   // the host's secret key file
//             "inputs": {"tcp://box-1.local:5600": "Z85 public key", ...},
//             "subscribers": ["Z85 public key", ...]}        // optional
// A key is 40 characters of Z85 (32 bytes). "host_key" names a file (relative to the session
// file) holding the host's secret key in Z85, readable by its owner only (mode 0600, as `mocap
// keys` writes it); the public key is derived from it. "inputs" gives every input endpoint of the
// session the public key of the server bound there (the box, hub or calibrator): mocapd's
// subscriber completes a handshake only with the holder of that key's secret, so a stranger on
// the endpoint is refused. "subscribers" (optional) lists the clients allowed on mocapd's output
// besides the host's own key; without it any client that knows the host's public key may read.
#ifndef MOCAP_DAEMON_CURVE_KEYS_H_
#define MOCAP_DAEMON_CURVE_KEYS_H_

#include <map>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

namespace mocap {

struct CurveKeys {
  std::string host_public, host_secret;           // Z85
  std::map<std::string, std::string> input_keys;  // endpoint -> its server's public key (Z85)
  std::vector<std::string> subscribers;           // Z85; empty: any client
  bool restrict_subscribers = false;              // "subscribers" given
};

// True for 40 characters of Z85 that decode to a 32-byte key.
bool IsCurveKey(const std::string& text);

// Reads a secret key file (Z85, whitespace around it ignored): refused when it is readable by
// group or others, or is not a key. Sets *public_key (derived) and *secret_key.
bool ReadSecretKeyFile(const std::string& path, std::string* public_key, std::string* secret_key,
                       std::string* error);

// The "curve" object of a session whose inputs are `inputs`; base is the session's folder.
// Every input needs a key, and every key an input; *error names what is wrong.
bool ReadCurveKeys(const nlohmann::json& j, const std::string& base,
                   const std::vector<std::string>& inputs, CurveKeys* out, std::string* error);

// True for an endpoint that stays on this machine: tcp on 127.0.0.0/8, localhost or [::1],
// ipc:// and inproc://. The streams of such endpoints may go without keys.
bool IsLocalEndpoint(const std::string& endpoint);

}  // namespace mocap

#endif  // MOCAP_DAEMON_CURVE_KEYS_H_
