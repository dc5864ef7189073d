#include "edge_health.h"

namespace mocap {

bool EdgeHealth::Add(const v1::Health& report, int64_t now_ns) {
  if (report.source().empty()) return false;
  reports_[report.source()] = {report, now_ns};
  return true;
}

void EdgeHealth::AppendTo(int64_t now_ns, v1::Health* health) const {
  for (const auto& [source, report] : reports_) {
    const bool fresh = now_ns - report.received_ns <= kStaleNs;
    for (const v1::StreamHealth& stream : report.health.streams()) {
      v1::StreamHealth* out = health->add_streams();
      *out = stream;
      out->set_stream(source + "/" + stream.stream());
      out->set_active(stream.active() && fresh);
    }
  }
}

}  // namespace mocap
