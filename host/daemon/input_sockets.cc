#include "input_sockets.h"

#include <zmq.h>

#include <cstring>
#include <iterator>
#include <zmq_addon.hpp>

namespace mocap {
namespace {

constexpr int kEvents = ZMQ_EVENT_HANDSHAKE_SUCCEEDED | ZMQ_EVENT_DISCONNECTED |
                        ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL | ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL |
                        ZMQ_EVENT_HANDSHAKE_FAILED_AUTH;

void SetUp(zmq::socket_t& sub, const Session& session, const std::string& endpoint) {
  sub.set(zmq::sockopt::rcvhwm, InputSockets::kSubscriberHwm);
  // A box that comes back is connected within 250 ms of binding (the crash drills: with a
  // 2 s back-off ceiling an IMU hub down for 1.5 s rejoined up to 2 s after its restart);
  // a retry every 250 ms to a box that stays off costs nothing.
  sub.set(zmq::sockopt::reconnect_ivl, 100);
  sub.set(zmq::sockopt::reconnect_ivl_max, 250);
  sub.set(zmq::sockopt::linger, 0);
  sub.set(zmq::sockopt::subscribe, "");
  // A box that hangs, or whose cable is pulled, leaves its TCP connection open: without a
  // heartbeat the host would hold that dead connection for good (a SUB sends nothing after
  // its subscription, so TCP never finds out) and never connect to the box when it is back.
  // A ping every second, unanswered for 3 s, closes it (a disconnection, InputLink) and
  // connecting anew begins.
  sub.set(zmq::sockopt::heartbeat_ivl, InputSockets::kHeartbeatMs);
  sub.set(zmq::sockopt::heartbeat_timeout, InputSockets::kHeartbeatTimeoutMs);
  if (session.curve) {
    sub.set(zmq::sockopt::curve_serverkey, session.curve->input_keys.at(endpoint));
    sub.set(zmq::sockopt::curve_publickey, session.curve->host_public);
    sub.set(zmq::sockopt::curve_secretkey, session.curve->host_secret);
  }
}

}  // namespace

bool InputSockets::Open(const Session& session, std::string* error) {
  try {
    for (size_t i = 0; i < session.inputs.size(); ++i) {
      const std::string& endpoint = session.inputs[i];
      zmq::socket_t& sub = subs_.emplace_back(context_, zmq::socket_type::sub);
      SetUp(sub, session, endpoint);
      const std::string monitor = "inproc://mocapd-input-" + std::to_string(i);
      if (zmq_socket_monitor(sub.handle(), monitor.c_str(), kEvents) != 0) throw zmq::error_t();
      monitors_.emplace_back(context_, zmq::socket_type::pair).connect(monitor);
      sub.connect(endpoint);
      links_.push_back(InputLink{endpoint});
    }
  } catch (const zmq::error_t& e) {
    *error = std::string("inputs: ") + e.what();
    return false;
  }
  for (auto& s : subs_) items_.push_back({s.handle(), 0, ZMQ_POLLIN, 0});
  for (auto& m : monitors_) items_.push_back({m.handle(), 0, ZMQ_POLLIN, 0});
  return true;
}

void InputSockets::Poll(std::chrono::milliseconds timeout) {
  try {
    zmq::poll(items_.data(), items_.size(), timeout);
  } catch (const zmq::error_t& e) {
    if (e.num() != EINTR) throw;  // a signal: the caller checks whether to stop
  }
}

void InputSockets::Drain(const std::function<void(size_t, std::vector<zmq::message_t>&)>& deliver) {
  std::vector<zmq::message_t> parts;
  for (size_t i = 0; i < subs_.size(); ++i) {
    for (;;) {
      parts.clear();
      if (!zmq::recv_multipart(subs_[i], std::back_inserter(parts), zmq::recv_flags::dontwait))
        break;
      deliver(i, parts);
    }
  }
}

void InputSockets::Watch(int64_t now_ns) {
  std::vector<zmq::message_t> parts;
  for (size_t i = 0; i < monitors_.size(); ++i) {
    for (;;) {
      parts.clear();
      if (!zmq::recv_multipart(monitors_[i], std::back_inserter(parts), zmq::recv_flags::dontwait))
        break;
      if (parts.empty() || parts[0].size() < sizeof(uint16_t)) continue;
      uint16_t event;
      std::memcpy(&event, parts[0].data(), sizeof event);
      OnEvent(i, event, now_ns);
    }
    InputLink& link = links_[i];
    if (link.retry_at_ns == 0 || now_ns < link.retry_at_ns) continue;
    link.retry_at_ns = 0;
    try {
      subs_[i].disconnect(link.endpoint);
    } catch (const zmq::error_t&) {  // already gone: connect anew all the same
    }
    subs_[i].connect(link.endpoint);
  }
}

void InputSockets::OnEvent(size_t i, uint16_t event, int64_t now_ns) {
  InputLink& link = links_[i];
  switch (event) {
    case ZMQ_EVENT_HANDSHAKE_SUCCEEDED:
      link.connected = true;
      link.handshakes++;
      break;
    case ZMQ_EVENT_DISCONNECTED:
      link.connected = false;
      closed_.push_back(i);
      break;
    case ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL:
    case ZMQ_EVENT_HANDSHAKE_FAILED_AUTH:
      link.retry_at_ns = now_ns + kRetryNs;  // libzmq does not retry these by itself
      [[fallthrough]];
    case ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL:
      link.connected = false;
      link.handshake_failures++;
      break;
    default:
      break;
  }
}

void InputSockets::AppendTo(v1::Health* health) const {
  for (const InputLink& link : links_) {
    v1::StreamHealth* s = health->add_streams();
    s->set_stream("link/" + link.endpoint);
    s->set_active(link.connected);
    s->set_handshake_failures(link.handshake_failures);
  }
}

}  // namespace mocap
