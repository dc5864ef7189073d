// The host's work between the transport and the publisher, without the transport: decode
// and check each message, map it to the session's cameras and IMUs, choose the subject,
// synchronise, apply calibrations, solve, and build PoseFrame and Health. The live daemon
// (daemon.h) feeds it from ZeroMQ; an offline solve feeds it a recording. Every bad input is
// counted and dropped.
//
// Its parts, each in its own file: InputPath (wire message -> synchronised frame: decoding,
// subject choice, synchronisation, drops and stream statistics), CalibrationQueue, SolveStep
// (or, in a session of several people, the SubjectTracker: one solve per person)
// (the solver with the IMUs it may use), EncodePoseFrame, StreamMonitor (Health), EdgeHealth
// (the edge processes' own reports, folded into Health).
#ifndef MOCAP_DAEMON_PIPELINE_H_
#define MOCAP_DAEMON_PIPELINE_H_

#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "calibration_queue.h"
#include "edge_health.h"
#include "input_path.h"
#include "mocap/subject_tracker.h"
#include "mocap/v1/calibration.pb.h"
#include "mocap/v1/health.pb.h"
#include "mocap/v1/pose_frame.pb.h"
#include "session.h"
#include "solve_step.h"

namespace mocap {

struct SolvedFrame {
  v1::PoseFrame pose;     // latency_ms is left to the publisher
  int64_t last_input_ns;  // arrival of the frame's newest input
};

class HostPipeline {
 public:
  static std::unique_ptr<HostPipeline> Create(Session session, std::string* error);

  // One message as received; now_ns is its arrival on the shared timebase; link: the input
  // connection it came on (InputPath). False when it was dropped: *why (may be null) says
  // why, for a log line.
  bool Feed(std::string_view type, std::string_view payload, int64_t now_ns,
            std::string* why = nullptr, int link = InputPath::kNoLink);
  // The input connection `link` closed (InputPath::LinkDown).
  void LinkDown(int link) { input_.LinkDown(link); }
  // Counts a message the transport could not even split into (type, payload).
  bool Reject(const std::string& reason, const std::string& detail, std::string* why) {
    return input_.monitor().Drop(reason, detail, why);
  }
  // Solves the frames ready at now_ns, oldest first.
  std::vector<SolvedFrame> Solve(int64_t now_ns);
  // The end of the input (an offline solve's last message): solves every frame still
  // pending, as InputPath::Flush releases them.
  std::vector<SolvedFrame> Flush();
  // The publisher reports each frame's latency (publication - last input), milliseconds.
  void RecordLatency(double ms) { input_.monitor().RecordLatency(ms); }
  // Health over the period since the previous call (which it starts anew).
  v1::Health Health(int64_t now_ns);

  // The session as in use: its skeleton, layout and IMU sites are the latest calibration's.
  const Session& session() const { return session_; }
  uint64_t calibrations_applied() const { return calibrations_.counts().applied; }
  // Per IMU of the session: solved with (its mounting and heading known).
  const std::vector<bool>& imus_calibrated() const { return step_.imus_calibrated(); }
  const std::map<std::string, uint64_t>& dropped() const { return input_.monitor().dropped(); }
  uint64_t frames_solved() const { return frames_solved_; }
  // The solver's heading corrections (rad, per IMU of the session), as Health reports them.
  const std::vector<double>& headings() const { return step_.solver().headings(); }

 private:
  HostPipeline(Session session, std::unique_ptr<Solver> solver);
  std::vector<SolvedFrame> SolveFrames(std::vector<SyncedFrame> frames);
  void SolvePeople(const SyncedFrame& f, std::vector<SolvedFrame>* out);
  bool FeedCalibration(const v1::Calibration& calibration, int64_t now_ns, std::string* why);
  // Applies the queued calibrations valid at or before time_ns.
  void ApplyCalibrations(int64_t time_ns);

  Session session_;
  SolveStep step_;
  InputPath input_;
  CalibrationQueue calibrations_;
  EdgeHealth edge_health_;
  std::unique_ptr<SubjectTracker> tracker_;   // a session of several people
  std::vector<std::pair<int, int>> suit_of_;  // per session IMU: (suit, its index there) or -1s
  uint64_t frames_solved_ = 0;
  uint64_t frames_failed_ = 0;  // refused by the solver (Health's frames_dropped)
};

}  // namespace mocap

#endif  // MOCAP_DAEMON_PIPELINE_H_
