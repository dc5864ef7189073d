// The ZAP handler (ZeroMQ's authentication protocol, RFC 27) of mocapd's output: when the
// session lists "subscribers", only clients holding one of those keys, or the host's own, may
// complete a CURVE handshake with the PoseFrame/Health publisher; the others are refused (status
// 400) and counted. It answers in the daemon's loop (Handle), on the context's
// inproc://zeromq.zap.01.
#ifndef MOCAP_DAEMON_ZAP_HANDLER_H_
#define MOCAP_DAEMON_ZAP_HANDLER_H_

#include <cstdint>
#include <set>
#include <string>
#include <vector>
#include <zmq.hpp>

namespace mocap {

class ZapHandler {
 public:
  // allowed: Z85 public keys. Binds the handler; throws zmq::error_t when it cannot.
  ZapHandler(zmq::context_t& context, const std::vector<std::string>& allowed);
  // Answers every request waiting.
  void Handle();
  zmq::socket_t& socket() { return socket_; }
  uint64_t refused() const { return refused_; }
  uint64_t accepted() const { return accepted_; }

 private:
  zmq::socket_t socket_;
  std::set<std::string> allowed_;  // Z85
  uint64_t refused_ = 0, accepted_ = 0;
};

}  // namespace mocap

#endif  // MOCAP_DAEMON_ZAP_HANDLER_H_
