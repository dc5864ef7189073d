// mocapd: the live host. Usage:
//   mocapd SESSION.json [--duration S] [--health-period S] [--quiet] [--realtime PRIORITY]
//          [--insecure]
// Prints one JSON line on exit: frames, latency percentiles, drops by reason, refused
// handshakes per input, whether it ran under real-time scheduling.
#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <map>
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

// A session without keys whose inputs leave this machine is refused (without --insecure):
// anyone on the network could then publish poses' inputs into the solve. An output that leaves
// it is only warned about (anyone could read the poses, none could change them).
bool CheckKeys(const mocap::Session& session, bool insecure, std::string* error) {
  if (session.curve) return true;
  for (const std::string& endpoint : session.inputs) {
    if (mocap::IsLocalEndpoint(endpoint)) continue;
    if (!insecure)
      return *error = "input " + endpoint +
                      " is not on this machine and the session has no \"curve\" keys: anyone "
                      "on the network could publish into the solve (README, \"Securing the "
                      "streams\"); --insecure runs without them",
             false;
    std::cerr << "mocapd: WARNING: --insecure: input " << endpoint
              << " is neither authenticated nor encrypted\n";
  }
  if (!mocap::IsLocalEndpoint(session.output))
    std::cerr << "mocapd: warning: output " << session.output
              << " is not encrypted: anyone who can reach it reads the poses\n";
  return true;
}

void PrintCounts(const char* name, const std::map<std::string, uint64_t>& counts) {
  std::cout << ", \"" << name << "\": {";
  bool first = true;
  for (const auto& [key, n] : counts) {
    std::cout << (first ? "" : ", ") << "\"" << key << "\": " << n;
    first = false;
  }
  std::cout << "}";
}

void PrintSummary(const mocap::DaemonSummary& summary, bool realtime) {
  std::cout << "{\"frames\": " << summary.frames
            << ", \"latency_p50_ms\": " << Percentile(summary.latency_ms, 0.5)
            << ", \"latency_p99_ms\": " << Percentile(summary.latency_ms, 0.99)
            << ", \"latency_max_ms\": " << Percentile(summary.latency_ms, 1.0)
            << ", \"subscribers_refused\": " << summary.subscribers_refused;
  PrintCounts("dropped", summary.dropped);
  PrintCounts("refused", summary.refused);
  std::cout << ", \"realtime\": " << (realtime ? "true" : "false") << "}" << std::endl;
}

// Bounds of the options: a duration of up to ~3 years keeps its nanoseconds in an int64;
// Health at most 10 times a second (each is a line on stderr and a message to every viewer).
constexpr double kMaxDurationS = 1e8, kMinHealthPeriodS = 0.1, kMaxHealthPeriodS = 3600;

// The whole of `text` as a number in [lo, hi]; false for anything else (text, nan, inf).
bool ParseNumber(const char* text, double lo, double hi, double* out) {
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (end == text || *end != '\0' || !std::isfinite(v) || v < lo || v > hi) return false;
  *out = v;
  return true;
}

// Fills `options`, `realtime_priority` and `insecure` from argv[2..]; false with a message on
// stderr.
bool ParseArguments(int argc, char** argv, mocap::DaemonOptions* options, int* realtime_priority,
                    bool* insecure) {
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quiet") {
      options->log_health = false;
      continue;
    }
    if (a == "--insecure") {
      *insecure = true;
      continue;
    }
    const bool takes_value = a == "--duration" || a == "--health-period" || a == "--realtime";
    if (!takes_value) return std::cerr << "mocapd: unknown argument " << a << "\n", false;
    if (i + 1 >= argc) return std::cerr << "mocapd: " << a << " needs a value\n", false;
    const char* value = argv[++i];
    double v = 0;
    if (a == "--duration" && !ParseNumber(value, 1e-3, kMaxDurationS, &options->duration_s))
      return std::cerr << "mocapd: --duration " << value
                       << ": a number of seconds, > 0 (omit it to run until stopped)\n",
             false;
    if (a == "--health-period" &&
        !ParseNumber(value, kMinHealthPeriodS, kMaxHealthPeriodS, &options->health_period_s))
      return std::cerr << "mocapd: --health-period " << value
                       << ": a number of seconds from 0.1 to 3600\n",
             false;
    if (a == "--realtime") {
      if (!ParseNumber(value, mocap::kMinRealtimePriority, mocap::kMaxRealtimePriority, &v) ||
          v != std::floor(v))
        return std::cerr << "mocapd: --realtime " << value << ": a priority from 1 to 99\n", false;
      *realtime_priority = static_cast<int>(v);
    }
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help")) {
    std::cerr << "usage: mocapd SESSION.json [--duration S] [--health-period S] [--quiet] "
                 "[--realtime PRIORITY] [--insecure]\n"
                 "  --duration S         stop after S seconds (> 0; default: until stopped)\n"
                 "  --health-period S    Health every S seconds (0.1 to 3600; default 1)\n"
                 "  --realtime PRIORITY  solve under SCHED_FIFO at PRIORITY (1-99); without the\n"
                 "                       permission, a warning and normal scheduling\n"
                 "  --insecure           run a session without keys whose inputs are not on\n"
                 "                       this machine (unauthenticated streams)\n";
    return argc < 2 ? 2 : 0;
  }
  mocap::DaemonOptions options;
  int realtime_priority = 0;  // 0: normal scheduling
  bool insecure = false;
  if (!ParseArguments(argc, argv, &options, &realtime_priority, &insecure)) return 2;
  std::string error;
  mocap::Session session;
  if (!mocap::LoadSession(argv[1], &session, &error))
    return std::cerr << "mocapd: " << error << "\n", 1;
  if (!CheckKeys(session, insecure, &error)) return std::cerr << "mocapd: " << error << "\n", 1;
  auto pipeline = mocap::HostPipeline::Create(std::move(session), &error);
  if (!pipeline) return std::cerr << "mocapd: " << error << "\n", 1;
  bool realtime = false;
  if (realtime_priority > 0 && !(realtime = mocap::EnterRealtime(realtime_priority, &error)))
    std::cerr << "mocapd: warning: " << error << "; solving at normal priority\n";
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  std::cerr << "mocapd: " << pipeline->session().rig.cameras.size() << " cameras, "
            << pipeline->session().imus.size() << " IMUs"
            << (pipeline->session().people > 1
                    ? ", up to " + std::to_string(pipeline->session().people) + " people, " +
                          std::to_string(pipeline->session().suits.size()) + " suits" +
                          (pipeline->session().suits.empty() ? " (the IMUs unused)" : "")
                    : std::string())
            << "; publishing on " << pipeline->session().output
            << (pipeline->session().curve ? "; streams authenticated and encrypted (CURVE)\n"
                                          : "; streams without keys\n");
  mocap::DaemonSummary summary;
  if (!mocap::RunDaemon(pipeline.get(), options, &g_stop, &summary, &error)) {
    return std::cerr << "mocapd: " << error << "\n", 1;
  }
  PrintSummary(summary, realtime);
  return 0;
}
