#include "daemon.h"

#include <chrono>
#include <iostream>
#include <zmq.hpp>
#include <zmq_addon.hpp>

#include "input_sockets.h"
#include "wire.h"
#include "zap_handler.h"

namespace mocap {
namespace {

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

// Binds the publisher, a CURVE server with the host's key pair when the session has keys;
// false with *error.
bool OpenPublisher(const Session& session, zmq::socket_t& pub, std::string* error) {
  try {
    pub.set(zmq::sockopt::sndhwm, kPublisherHwm);
    pub.set(zmq::sockopt::linger, 200);
    if (session.curve) {
      pub.set(zmq::sockopt::curve_server, true);
      pub.set(zmq::sockopt::curve_secretkey, session.curve->host_secret);
    }
    pub.bind(session.output);
  } catch (const zmq::error_t& e) {
    *error = std::string("output ") + session.output + ": " + e.what();
    return false;
  }
  return true;
}

// Feeds a message as received on input `link`, stamped with its arrival.
void Deliver(size_t link, std::vector<zmq::message_t>& parts, HostPipeline* pipeline) {
  std::string why;
  const int64_t now = NowNs();
  const bool ok =
      parts.size() == 2
          ? pipeline->Feed(parts[0].to_string_view(), parts[1].to_string_view(), now, &why,
                           static_cast<int>(link))
          : pipeline->Reject("undecodable", std::to_string(parts.size()) + " frames, expected 2",
                             &why);
  if (!ok) LogDrop(why, pipeline->dropped());
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

void PublishHealth(zmq::socket_t& pub, HostPipeline* pipeline, const InputSockets& inputs,
                   int64_t now, bool log) {
  v1::Health health = pipeline->Health(now);
  inputs.AppendTo(&health);
  Send(pub, health);
  if (log) {
    std::cerr << "mocapd: " << health.frames_solved() << " frames, latency p50 "
              << health.latency_p50_ms() << " ms p99 " << health.latency_p99_ms() << " ms\n";
  }
}

// Logs each input's refused handshakes as they grow (the first ones, then every 100th).
void LogRefusals(const InputSockets& inputs, std::vector<uint64_t>* logged) {
  logged->resize(inputs.links().size());
  for (size_t i = 0; i < inputs.links().size(); ++i) {
    const InputLink& link = inputs.links()[i];
    const uint64_t n = link.handshake_failures;
    if (n == (*logged)[i]) continue;
    if (n <= 3 || n / 100 != (*logged)[i] / 100)
      std::cerr << "mocapd: refused a publisher on " << link.endpoint << " (" << n
                << " refused): not the key the session expects there\n";
    (*logged)[i] = n;
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
  const Session& session = pipeline->session();
  std::unique_ptr<ZapHandler> zap;
  if (session.curve && session.curve->restrict_subscribers) {
    std::vector<std::string> allowed = session.curve->subscribers;
    allowed.push_back(session.curve->host_public);
    try {
      zap = std::make_unique<ZapHandler>(context, allowed);
    } catch (const zmq::error_t& e) {
      return *error = std::string("output's ZAP handler: ") + e.what(), false;
    }
  }
  InputSockets inputs(context);
  zmq::socket_t pub(context, zmq::socket_type::pub);
  if (!inputs.Open(session, error) || !OpenPublisher(session, pub, error)) return false;
  const int64_t start = NowNs();
  const auto period = static_cast<int64_t>(options.health_period_s * 1e9);
  int64_t next_health = start + period;
  std::vector<uint64_t> logged;
  while (!stop->load()) {
    inputs.Poll(std::chrono::milliseconds(kPollMs));
    if (zap) zap->Handle();
    inputs.Drain(
        [&](size_t link, std::vector<zmq::message_t>& parts) { Deliver(link, parts, pipeline); });
    PublishPoses(pub, pipeline, summary);
    const int64_t now = NowNs();
    inputs.Watch(now);
    for (size_t link : inputs.TakeClosed()) pipeline->LinkDown(static_cast<int>(link));
    LogRefusals(inputs, &logged);
    if (now >= next_health) {
      PublishHealth(pub, pipeline, inputs, now, options.log_health);
      next_health += period;
    }
    if (options.duration_s > 0 && now - start >= static_cast<int64_t>(options.duration_s * 1e9))
      break;
  }
  summary->dropped = pipeline->dropped();
  for (const InputLink& link : inputs.links())
    summary->refused[link.endpoint] = link.handshake_failures;
  if (zap) summary->subscribers_refused = zap->refused();
  return true;
}

}  // namespace mocap
