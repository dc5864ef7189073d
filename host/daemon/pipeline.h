// The host's work between the transport and the publisher, without the transport:
// decode and check each message, map it to the session's cameras and IMUs, synchronise,
// solve, and build PoseFrame and Health. The live daemon (daemon.h) feeds it from
// ZeroMQ; an offline solve feeds it a recording. Every bad input is counted and dropped.
#ifndef MOCAP_DAEMON_PIPELINE_H_
#define MOCAP_DAEMON_PIPELINE_H_

#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "mocap/stream_sync.h"
#include "mocap/v1/calibration.pb.h"
#include "mocap/v1/health.pb.h"
#include "mocap/v1/imu_batch.pb.h"
#include "mocap/v1/keypoint_frame.pb.h"
#include "mocap/v1/pose_frame.pb.h"
#include "session.h"
#include "wire.h"

namespace mocap {

struct SolvedFrame {
  v1::PoseFrame pose;     // latency_ms is left to the publisher
  int64_t last_input_ns;  // arrival of the frame's newest input
};

class HostPipeline {
 public:
  static std::unique_ptr<HostPipeline> Create(Session session, std::string* error);

  // One message as received; now_ns is its arrival on the shared timebase. False when it
  // was dropped: *why (may be null) says why, for a log line.
  bool Feed(std::string_view type, std::string_view payload, int64_t now_ns,
            std::string* why = nullptr);
  // Counts a message the transport could not even split into (type, payload).
  bool Reject(const std::string& reason, const std::string& detail, std::string* why) {
    return Drop(reason, detail, why);
  }
  // Solves the frames ready at now_ns, oldest first.
  std::vector<SolvedFrame> Solve(int64_t now_ns);
  // The publisher reports each frame's latency (publication - last input), milliseconds.
  void RecordLatency(double ms) { latencies_ms_.push_back(ms); }
  // Health over the period since the previous call (which it starts anew).
  v1::Health Health(int64_t now_ns);

  // The session as in use: its skeleton, layout and IMU sites are the latest calibration's.
  const Session& session() const { return session_; }
  uint64_t calibrations_applied() const { return calibrations_applied_; }
  // Per IMU of the session: solved with (its mounting and heading known).
  const std::vector<bool>& imus_calibrated() const { return imu_calibrated_; }
  const std::map<std::string, uint64_t>& dropped() const { return dropped_; }  // by reason
  uint64_t frames_solved() const { return frames_solved_; }

 private:
  struct StreamStats {
    uint64_t received_in_period = 0, lost = 0, invalid = 0;
    std::optional<uint64_t> last_counter;  // frame index / sequence / packet counter
    int64_t last_time_ns = 0;              // the sender's time of that message
    std::vector<double> latency_ms;        // arrival - capture, this period
  };
  HostPipeline(Session session, std::unique_ptr<Solver> solver);
  bool Drop(const std::string& reason, const std::string& detail, std::string* why);
  bool FeedKeypoints(const v1::KeypointFrame& frame, int64_t now_ns, std::string* why);
  bool FeedImus(const v1::ImuBatch& batch, int64_t now_ns, std::string* why);
  // A calibration to apply from its valid_from_ns on (pending_), when it fits the session;
  // one its source sent before (a calibrator repeats its latest for late joiners) is skipped.
  bool FeedCalibration(const v1::Calibration& calibration, std::string* why);
  // Applies the pending calibrations valid at or before time_ns.
  void ApplyCalibrations(int64_t time_ns);
  // The subject among the frame's persons: nearest to the current pose's projection once
  // tracking, else the most confident.
  int ChooseSubject(const v1::KeypointFrame& frame, int camera) const;
  // Counts a message of a stream: its transport latency, and gaps in the sender's counter
  // (lost messages). A counter behind the last one is a late message when the message is
  // older too (it is no longer lost), a restart of the sender when it is newer.
  void Count(StreamStats* stats, uint64_t counter, uint64_t modulo, int64_t time_ns,
             int64_t now_ns);

  struct PendingCalibration {
    int64_t valid_from_ns;
    Skeleton skeleton;
    KeypointLayout layout;
    std::vector<ImuSite> imus;  // the session's IMU set, in its order
    std::vector<bool> calibrated;
  };

  Session session_;
  std::unique_ptr<Solver> solver_;
  std::vector<bool> imu_calibrated_;
  std::vector<PendingCalibration> pending_;  // by valid_from_ns
  uint64_t calibrations_applied_ = 0, calibrations_rejected_ = 0, calibrations_repeated_ = 0;
  std::map<std::string, uint64_t> calibration_sequences_;  // by source: the newest taken
  StreamStats calibration_stats_;
  StreamSynchroniser sync_;
  std::unordered_map<std::string, int> camera_index_, imu_index_;
  std::vector<StreamStats> camera_stats_, imu_stats_;
  std::map<std::string, StreamStats> hub_stats_;
  std::map<std::string, uint64_t> dropped_;
  std::vector<double> latencies_ms_;
  uint64_t frames_solved_ = 0, frames_in_period_ = 0;
  std::optional<int64_t> period_start_ns_;
};

}  // namespace mocap

#endif  // MOCAP_DAEMON_PIPELINE_H_
