// Wire messages -> synchronised solver frames: the one way the host turns the studio's
// streams into frames, whether live (mocapd, through HostPipeline) or offline (a recording,
// through the bindings). Each KeypointFrame and ImuBatch is checked (wire.h), mapped to the
// session's cameras and IMUs (InputDecoder), its subject chosen (SubjectSelector), and handed
// to the StreamSynchroniser; what is dropped is counted by reason, and each stream's
// statistics kept, in the StreamMonitor the host's Health is built from.
#ifndef MOCAP_DAEMON_INPUT_PATH_H_
#define MOCAP_DAEMON_INPUT_PATH_H_

#include <google/protobuf/message.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "input_decoder.h"
#include "mocap/solver.h"
#include "mocap/stream_sync.h"
#include "stream_monitor.h"
#include "subject_selector.h"

namespace mocap {

class InputPath {
 public:
  static constexpr int kNoLink = -1;

  // min_confidence: keypoints at or below are not detected (SolverOptions::min_confidence).
  // everyone: a session of several people: every person of every camera is synchronised
  // (SyncedFrame::people) and none chosen as the subject.
  InputPath(const Rig& rig, const std::vector<ImuSite>& imus, const KeypointLayout& layout,
            const SyncOptions& sync, double min_confidence, bool everyone = false);

  // Feed* take one message received at now_ns (the arrival clock). `tracker` (may be null):
  // a solver whose pose, once initialised, picks the subject among several persons. False
  // when the message was dropped: *why (may be null) is "reason: detail" for a log line.

  // `link`: the connection it came on (mocapd's input socket), or kNoLink (a recording).

  // A message as received (type frame and payload), checked by wire::DecodeMessage.
  bool Feed(std::string_view type, std::string_view payload, int64_t now_ns, const Solver* tracker,
            std::string* why, int link = kNoLink);
  // A decoded message: a KeypointFrame or an ImuBatch, anything else is "not_an_input".
  bool Feed(const google::protobuf::Message& message, int64_t now_ns, const Solver* tracker,
            std::string* why, int link = kNoLink);
  bool FeedKeypoints(const v1::KeypointFrame& frame, int64_t now_ns, const Solver* tracker,
                     std::string* why, int link = kNoLink);
  // A batch's samples are taken one by one: a late or duplicated one is counted
  // ("late_or_duplicate") and the rest kept; false only when sensors are not in the set.
  bool FeedImus(const v1::ImuBatch& batch, int64_t now_ns, std::string* why, int link = kNoLink);

  // The connection `link` closed: the streams last heard on it are inactive at once, so no
  // frame waits for a box that is gone (StreamSynchroniser::MarkLinkDown).
  void LinkDown(int link);

  // Frames ready at now_ns, oldest first.
  std::vector<SyncedFrame> TakeReady(int64_t now_ns) { return sync_.TakeReady(now_ns); }
  // The end of the input (StreamSynchroniser::Flush): every frame still pending.
  std::vector<SyncedFrame> Flush() { return sync_.Flush(); }

  const StreamSynchroniser& sync() const { return sync_; }
  const InputDecoder& decoder() const { return decoder_; }
  // Drops by reason and per-stream statistics; HostPipeline counts its own drops, solved
  // frames and latencies there too, and builds Health from it.
  StreamMonitor& monitor() { return monitor_; }
  const StreamMonitor& monitor() const { return monitor_; }

 private:
  const Rig rig_;
  const bool everyone_;
  InputDecoder decoder_;
  SubjectSelector selector_;
  StreamSynchroniser sync_;
  StreamMonitor monitor_;
  std::vector<int> camera_link_, imu_link_;  // the link each stream was last heard on
};

}  // namespace mocap

#endif  // MOCAP_DAEMON_INPUT_PATH_H_
