// What the host tells about its inputs: every dropped message counted by reason, each
// stream's statistics (stream_stats.h), and once a period the Health message
// (proto/mocap/v1/health.proto) with the synchroniser's and the calibrations' counts.
#ifndef MOCAP_DAEMON_STREAM_MONITOR_H_
#define MOCAP_DAEMON_STREAM_MONITOR_H_

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "calibration_queue.h"
#include "mocap/stream_sync.h"
#include "mocap/v1/health.pb.h"
#include "stream_stats.h"

namespace mocap {

// What Health reports besides the monitor's own counts.
struct HealthInputs {
  const StreamSynchroniser* sync = nullptr;
  std::vector<double> headings;  // rad, per IMU (Solver::headings)
  std::vector<bool> distrusted;  // per IMU (Solver::distrusted)
  CalibrationCounts calibrations;
  bool calibration_active = false;  // any IMU is solved with
  uint64_t frames_solved = 0;       // since the start
  uint64_t frames_failed = 0;       // of those, refused by the solver (status FAILED)
};

class StreamMonitor {
 public:
  // The names of the session's cameras and IMUs, in the synchroniser's order.
  StreamMonitor(std::vector<std::string> cameras, std::vector<std::string> imus);

  // Counts a dropped message under `reason`; returns false, with *why (may be null) set to
  // "reason: detail" for the log line.
  bool Drop(const std::string& reason, const std::string& detail, std::string* why);
  void CountDropped(const std::string& reason, uint64_t n = 1) { dropped_[reason] += n; }

  StreamStats& camera(int c) { return cameras_[c]; }
  StreamStats& imu(int i) { return imus_[i]; }
  StreamStats& hub(const std::string& id) { return hubs_[id]; }
  StreamStats& calibration() { return calibration_; }
  void CountSolvedFrame() { frames_in_period_++; }
  // The publisher reports each frame's latency (publication - last input), milliseconds.
  void RecordLatency(double ms) { latencies_ms_.push_back(ms); }

  const std::map<std::string, uint64_t>& dropped() const { return dropped_; }  // by reason

  // Health over the period since the previous call (which it starts anew).
  v1::Health Health(int64_t now_ns, const HealthInputs& in);

 private:
  // Appends a stream's entry and starts its period anew. repeats_drop: a duplicate counts
  // as dropped (not for calibrations, repeated by design).
  void AddStream(const std::string& name, bool active, const StreamCounts* counts,
                 bool repeats_drop, StreamStats* stats, v1::Health* h) const;
  void AddCalibration(const HealthInputs& in, v1::Health* h);
  void AddInputAndPose(const HealthInputs& in, v1::Health* h);

  std::vector<std::string> camera_names_, imu_names_;
  std::vector<StreamStats> cameras_, imus_;
  std::map<std::string, StreamStats> hubs_;
  StreamStats calibration_;
  std::map<std::string, uint64_t> dropped_;
  std::vector<double> latencies_ms_;
  uint64_t frames_in_period_ = 0;
  double period_s_ = 1.0;
  std::optional<int64_t> period_start_ns_;
};

}  // namespace mocap

#endif  // MOCAP_DAEMON_STREAM_MONITOR_H_
