// mocapd's subscribers: one SUB socket per input of the session, each watched by a socket
// monitor, so what happens on each input's connection is known by its endpoint. With the
// session's CURVE keys (curve_keys.h) each socket is a CURVE client holding the host's key pair
// and expecting its input's server key: a publisher on the endpoint without that key's secret
// fails the handshake, none of its messages reaches the host, and the refusal is counted
// (libzmq's ZMQ_EVENT_HANDSHAKE_FAILED_* events). libzmq gives up on a connection whose handshake
// failed on a protocol error or was refused by the server's authentication; such an input is
// connected anew after kRetryNs, so the real box is heard again once the stranger is gone.
#ifndef MOCAP_DAEMON_INPUT_SOCKETS_H_
#define MOCAP_DAEMON_INPUT_SOCKETS_H_

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>
#include <zmq.hpp>

#include "mocap/v1/health.pb.h"
#include "session.h"

namespace mocap {

struct InputLink {
  std::string endpoint;
  bool connected = false;           // a handshake succeeded and the connection is up
  uint64_t handshakes = 0;          // handshakes that succeeded
  uint64_t handshake_failures = 0;  // refused: wrong key, no CURVE, or refused by the server
  int64_t retry_at_ns = 0;          // 0, or when to connect anew after a failure libzmq gave up on
};

class InputSockets {
 public:
  static constexpr int kSubscriberHwm = 20000;  // messages (~3 s of 8 cameras + a hub)
  static constexpr int64_t kRetryNs = 1'000'000'000;
  static constexpr int kHeartbeatMs = 1000, kHeartbeatTimeoutMs = 3000;  // see SetUp

  explicit InputSockets(zmq::context_t& context) : context_(context) {}

  // Connects a socket (with its monitor) to every input; false with *error.
  bool Open(const Session& session, std::string* error);
  // Waits up to timeout for a message or an event on any input.
  void Poll(std::chrono::milliseconds timeout);
  // Hands every message waiting on any input to deliver, with the input's index (its link).
  void Drain(const std::function<void(size_t, std::vector<zmq::message_t>&)>& deliver);
  // Reads the monitors' events (counting refused handshakes) and connects anew the inputs due.
  void Watch(int64_t now_ns);
  // The inputs whose connection closed since the last call (by index, as Drain gives them).
  std::vector<size_t> TakeClosed() { return std::exchange(closed_, {}); }
  // One "link/<endpoint>" stream per input: active while connected, its refused handshakes.
  void AppendTo(v1::Health* health) const;
  const std::vector<InputLink>& links() const { return links_; }

 private:
  void OnEvent(size_t i, uint16_t event, int64_t now_ns);

  zmq::context_t& context_;
  std::vector<zmq::socket_t> subs_, monitors_;
  std::vector<InputLink> links_;
  std::vector<zmq::pollitem_t> items_;
  std::vector<size_t> closed_;
};

}  // namespace mocap

#endif  // MOCAP_DAEMON_INPUT_SOCKETS_H_
