#include "daemon.h"

#include <chrono>
#include <iostream>
#include <zmq.hpp>
#include <zmq_addon.hpp>

#include "wire.h"

namespace mocap {
namespace {

constexpr int kSubscriberHwm = 20000;  // messages (~3 s of 8 cameras + a hub)
constexpr int kPublisherHwm = 2000;
constexpr int kPollMs = 2;

void Send(zmq::socket_t& socket, const google::protobuf::Message& message) {
  const std::string type = wire::TypeName(message);
  const std::string payload = message.SerializeAsString();
  // Non-blocking: at the high-water mark a PUB socket drops, it never stalls the solve.
  socket.send(zmq::buffer(type), zmq::send_flags::sndmore | zmq::send_flags::dontwait);
  socket.send(zmq::buffer(payload), zmq::send_flags::dontwait);
}

// Logs the first drops of each reason, then every 1000th.
void LogDrop(const std::string& why, const std::map<std::string, uint64_t>& dropped) {
  const std::string reason = why.substr(0, why.find(':'));
  const auto it = dropped.find(reason);
  const uint64_t n = it == dropped.end() ? 0 : it->second;
  if (n <= 10 || n % 1000 == 0)
    std::cerr << "mocapd: dropped (" << n << " " << reason << "): " << why << "\n";
}

// Connects the subscriber to every input and binds the publisher; false with *error.
bool OpenSockets(const Session& session, zmq::socket_t& sub, zmq::socket_t& pub,
                 std::string* error) {
  try {
    sub.set(zmq::sockopt::rcvhwm, kSubscriberHwm);
    // A box that comes back is connected within 250 ms of binding (the crash drills: with a
    // 2 s back-off ceiling an IMU hub down for 1.5 s rejoined up to 2 s after its restart);
    // a retry every 250 ms to a box that stays off costs nothing.
    sub.set(zmq::sockopt::reconnect_ivl, 100);
    sub.set(zmq::sockopt::reconnect_ivl_max, 250);
    sub.set(zmq::sockopt::linger, 0);
    sub.set(zmq::sockopt::subscribe, "");
    for (const std::string& endpoint : session.inputs) sub.connect(endpoint);
    pub.set(zmq::sockopt::sndhwm, kPublisherHwm);
    pub.set(zmq::sockopt::linger, 200);
    pub.bind(session.output);
  } catch (const zmq::error_t& e) {
    *error = std::string("sockets: ") + e.what();
    return false;
  }
  return true;
}

// Feeds every message waiting on the subscriber, stamped with its arrival.
void Drain(zmq::socket_t& sub, HostPipeline* pipeline) {
  std::vector<zmq::message_t> parts;
  for (;;) {
    parts.clear();
    if (!zmq::recv_multipart(sub, std::back_inserter(parts), zmq::recv_flags::dontwait)) return;
    std::string why;
    const int64_t now = NowNs();
    const bool ok =
        parts.size() == 2
            ? pipeline->Feed(parts[0].to_string_view(), parts[1].to_string_view(), now, &why)
            : pipeline->Reject("undecodable", std::to_string(parts.size()) + " frames, expected 2",
                               &why);
    if (!ok) LogDrop(why, pipeline->dropped());
  }
}

// Solves the frames ready now and publishes them with their latency.
void PublishPoses(zmq::socket_t& pub, HostPipeline* pipeline, DaemonSummary* summary) {
  for (SolvedFrame& f : pipeline->Solve(NowNs())) {
    const double latency = 1e-6 * static_cast<double>(NowNs() - f.last_input_ns);
    f.pose.set_latency_ms(latency);
    Send(pub, f.pose);
    pipeline->RecordLatency(latency);
    summary->latency_ms.push_back(latency);
    summary->frames++;
  }
}

void PublishHealth(zmq::socket_t& pub, HostPipeline* pipeline, int64_t now, bool log) {
  const v1::Health health = pipeline->Health(now);
  Send(pub, health);
  if (log) {
    std::cerr << "mocapd: " << health.frames_solved() << " frames, latency p50 "
              << health.latency_p50_ms() << " ms p99 " << health.latency_p99_ms() << " ms\n";
  }
}

}  // namespace

int64_t NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

bool RunDaemon(HostPipeline* pipeline, const DaemonOptions& options, const std::atomic<bool>* stop,
               DaemonSummary* summary, std::string* error) {
  zmq::context_t context(1);
  zmq::socket_t sub(context, zmq::socket_type::sub), pub(context, zmq::socket_type::pub);
  if (!OpenSockets(pipeline->session(), sub, pub, error)) return false;
  const int64_t start = NowNs();
  const auto period = static_cast<int64_t>(options.health_period_s * 1e9);
  int64_t next_health = start + period;
  zmq::pollitem_t items[] = {{sub.handle(), 0, ZMQ_POLLIN, 0}};
  while (!stop->load()) {
    try {
      zmq::poll(items, 1, std::chrono::milliseconds(kPollMs));
    } catch (const zmq::error_t& e) {
      if (e.num() == EINTR) continue;  // a signal: the loop checks *stop
      throw;
    }
    Drain(sub, pipeline);
    PublishPoses(pub, pipeline, summary);
    const int64_t now = NowNs();
    if (now >= next_health) {
      PublishHealth(pub, pipeline, now, options.log_health);
      next_health += period;
    }
    if (options.duration_s > 0 && now - start >= static_cast<int64_t>(options.duration_s * 1e9))
      break;
  }
  summary->dropped = pipeline->dropped();
  return true;
}

}  // namespace mocap
