// mocapd: the live host. Usage:
//   mocapd SESSION.json [--duration S] [--health-period S] [--quiet] [--realtime PRIORITY]
// Prints one JSON line on exit: frames, latency percentiles, drops by reason, whether it ran
// under real-time scheduling.
#include <algorithm>
#include <csignal>
#include <cstring>
#include <iostream>
#include <string>

#include "daemon.h"
#include "realtime.h"

namespace {

std::atomic<bool> g_stop{false};

void OnSignal(int) { g_stop = true; }

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(p * static_cast<double>(v.size())))];
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help")) {
    std::cerr << "usage: mocapd SESSION.json [--duration S] [--health-period S] [--quiet] "
                 "[--realtime PRIORITY]\n"
                 "  --realtime PRIORITY  solve under SCHED_FIFO at PRIORITY (1-99); without the\n"
                 "                       permission, a warning and normal scheduling\n";
    return argc < 2 ? 2 : 0;
  }
  mocap::DaemonOptions options;
  int realtime_priority = 0;  // 0: normal scheduling
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--duration" && i + 1 < argc)
      options.duration_s = std::atof(argv[++i]);
    else if (a == "--health-period" && i + 1 < argc)
      options.health_period_s = std::atof(argv[++i]);
    else if (a == "--quiet")
      options.log_health = false;
    else if (a == "--realtime" && i + 1 < argc) {
      realtime_priority = std::atoi(argv[++i]);
      if (realtime_priority < mocap::kMinRealtimePriority ||
          realtime_priority > mocap::kMaxRealtimePriority)
        return std::cerr << "mocapd: --realtime " << argv[i] << ": a priority from 1 to 99\n", 2;
    } else
      return std::cerr << "mocapd: unknown argument " << a << "\n", 2;
  }
  std::string error;
  mocap::Session session;
  if (!mocap::LoadSession(argv[1], &session, &error))
    return std::cerr << "mocapd: " << error << "\n", 1;
  auto pipeline = mocap::HostPipeline::Create(std::move(session), &error);
  if (!pipeline) return std::cerr << "mocapd: " << error << "\n", 1;
  bool realtime = false;
  if (realtime_priority > 0 && !(realtime = mocap::EnterRealtime(realtime_priority, &error)))
    std::cerr << "mocapd: warning: " << error << "; solving at normal priority\n";
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  std::cerr << "mocapd: " << pipeline->session().rig.cameras.size() << " cameras, "
            << pipeline->session().imus.size() << " IMUs; publishing on "
            << pipeline->session().output << "\n";
  mocap::DaemonSummary summary;
  if (!mocap::RunDaemon(pipeline.get(), options, &g_stop, &summary, &error)) {
    return std::cerr << "mocapd: " << error << "\n", 1;
  }
  std::cout << "{\"frames\": " << summary.frames
            << ", \"latency_p50_ms\": " << Percentile(summary.latency_ms, 0.5)
            << ", \"latency_p99_ms\": " << Percentile(summary.latency_ms, 0.99)
            << ", \"latency_max_ms\": " << Percentile(summary.latency_ms, 1.0)
            << ", \"dropped\": {";
  bool first = true;
  for (const auto& [reason, n] : summary.dropped) {
    std::cout << (first ? "" : ", ") << "\"" << reason << "\": " << n;
    first = false;
  }
  std::cout << "}, \"realtime\": " << (realtime ? "true" : "false") << "}" << std::endl;
  return 0;
}
