// What the edge processes report of themselves: an IMU hub publishes its own Health (its nodes'
// samples, losses and clock fits, its bus's errors) beside its ImuBatches. The host keeps each
// source's latest report and adds its streams to the host's Health, prefixed by the source
// ("hub0/imu/pelvis", "hub0/bus"), so one subscriber sees the whole studio.
#ifndef MOCAP_DAEMON_EDGE_HEALTH_H_
#define MOCAP_DAEMON_EDGE_HEALTH_H_

#include <cstdint>
#include <map>
#include <string>

#include "mocap/v1/health.pb.h"

namespace mocap {

class EdgeHealth {
 public:
  // A report older than this leaves its streams inactive (the edge process went quiet).
  static constexpr int64_t kStaleNs = 3'000'000'000;

  // Keeps the report received at now_ns; false (nothing kept) when it names no source.
  bool Add(const v1::Health& report, int64_t now_ns);
  // Appends every source's streams, prefixed by the source, to *health.
  void AppendTo(int64_t now_ns, v1::Health* health) const;

 private:
  struct Report {
    v1::Health health;
    int64_t received_ns;
  };
  std::map<std::string, Report> reports_;
};

}  // namespace mocap

#endif  // MOCAP_DAEMON_EDGE_HEALTH_H_
