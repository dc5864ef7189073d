// Synchronisation of the camera and IMU streams into solver frames.
//
// Camera frames are grouped by capture time (boxes share a trigger, so one frame's
// timestamps agree to well under half a period). A frame is handed over when every
// active camera delivered it or moved past it and every active IMU has a sample at or
// after its time; at the latest when `now` passes its time + max_wait. IMU orientations
// are slerped, accelerations interpolated linearly, to the frame's time. A stream is
// active while it delivered within stale_after (every configured stream is expected from
// the first input of any): a stopped box never stalls the solve, and counts again from its
// first new message. A stream whose connection closed (MarkLinkDown) is inactive at once. Late
// (after their frame was handed over) and duplicated inputs are counted and dropped; out-of-order
// ones are put in order. With no camera active, frames are clocked from the IMUs at
// imu_only_rate_hz.
//
// Times are int64 nanoseconds on the shared timebase; `now_ns` is the arrival time
// (live: the host's clock; replay: the recorded arrival), so a replay is deterministic.
#ifndef MOCAP_STREAM_SYNC_H_
#define MOCAP_STREAM_SYNC_H_

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "mocap/observations.h"

namespace mocap {

struct SyncOptions {
  int64_t group_tolerance_ns = 4'000'000;  // < half a frame period at 120 fps
  int64_t max_wait_ns = 25'000'000;        // after the frame's time, on the arrival clock
  int64_t stale_after_ns = 300'000'000;    // silence after which a stream is inactive
  int64_t imu_max_gap_ns = 40'000'000;     // interpolate between samples at most this far apart
  int64_t imu_max_hold_ns = 15'000'000;    // use the nearest sample this far from the frame
  int64_t imu_history_ns = 1'000'000'000;  // samples kept per sensor
  double imu_only_rate_hz = 60.0;          // frame clock when no camera is active
  int max_pending_frames = 120;            // beyond this the oldest frame is handed over
  bool IsValid(std::string* error) const;

  // Every field once (as SolverOptions::VisitFields): the bindings' attributes and the
  // session's "sync" keys (daemon/options_json.h) are derived from it.
  template <typename Visit>
  static void VisitFields(Visit&& visit) {
    visit("group_tolerance_ns", &SyncOptions::group_tolerance_ns);
    visit("max_wait_ns", &SyncOptions::max_wait_ns);
    visit("stale_after_ns", &SyncOptions::stale_after_ns);
    visit("imu_max_gap_ns", &SyncOptions::imu_max_gap_ns);
    visit("imu_max_hold_ns", &SyncOptions::imu_max_hold_ns);
    visit("imu_history_ns", &SyncOptions::imu_history_ns);
    visit("imu_only_rate_hz", &SyncOptions::imu_only_rate_hz);
    visit("max_pending_frames", &SyncOptions::max_pending_frames);
  }
};

struct CameraInput {
  int camera = 0;  // index into the rig
  int64_t time_ns = 0;
  bool detected = true;               // false: the frame only clocks the solve (HS mode)
  std::vector<Keypoint2D> keypoints;  // the subject's, in layout order; empty: nobody
  // Every person the camera found (sessions of several people, instead of `keypoints`).
  std::vector<std::vector<Keypoint2D>> persons;
};

struct ImuInput {
  int imu = 0;  // index into the IMU sites
  int64_t time_ns = 0;
  Eigen::Quaterniond orientation{1, 0, 0, 0};
  Eigen::Vector3d acceleration{0, 0, 0};
  bool has_orientation = true, has_acceleration = true;
};

struct SyncedFrame {
  int64_t time_ns = 0;
  // timestamp: seconds since the first frame (epoch_ns()).
  FrameObservations observations;
  std::vector<CameraObservation> people;  // every person of every camera (several people)
  int64_t last_input_ns = 0;              // arrival of the newest input the frame used
  int64_t released_ns = 0;                // `now` when it was handed over
  std::vector<int> cameras_clocked;  // cameras that delivered the frame (with or without keypoints)
  std::vector<int> cameras_detected;  // of those, the ones that ran detection (not HS-only frames)
};

struct StreamCounts {
  uint64_t received = 0, late = 0, duplicates = 0, out_of_order = 0;
  std::optional<int64_t> last_arrival_ns;
  bool link_down = false;  // the connection that carried it closed; until its next input
};

class StreamSynchroniser {
 public:
  StreamSynchroniser(int num_cameras, int num_imus, SyncOptions options);

  // Indices must be in range (the caller maps names and counts unknown ones). False when
  // the input was dropped (late or duplicate; counted in the stream's counts).
  bool AddCamera(CameraInput input, int64_t now_ns);
  bool AddImu(const ImuInput& input, int64_t now_ns);
  // The connection that carried these streams closed: no frame waits for them any more
  // (they would only be stale after stale_after); each is active again from its next input.
  void MarkLinkDown(const std::vector<int>& cameras, const std::vector<int>& imus);
  // Frames ready at now_ns, oldest first.
  std::vector<SyncedFrame> TakeReady(int64_t now_ns);
  // The end of the input (an offline solve): the frames ready max_wait after the newest
  // arrival, as the live host would release them had nothing more come, then every frame
  // still pending. Empty before any input.
  std::vector<SyncedFrame> Flush();

  int num_cameras() const { return static_cast<int>(cameras_.size()); }
  int num_imus() const { return static_cast<int>(imus_.size()); }
  bool CameraActive(int c, int64_t now_ns) const { return Active(cameras_[c].counts, now_ns); }
  bool ImuActive(int i, int64_t now_ns) const { return Active(imus_[i].counts, now_ns); }
  const StreamCounts& camera_counts(int c) const { return cameras_[c].counts; }
  const StreamCounts& imu_counts(int i) const { return imus_[i].counts; }
  uint64_t frames_released() const { return frames_released_; }
  uint64_t frames_forced() const { return frames_forced_; }  // released by deadline or overflow
  int pending() const { return static_cast<int>(pending_.size()); }
  std::optional<int64_t> epoch_ns() const { return epoch_ns_; }
  const SyncOptions& options() const { return options_; }

 private:
  struct Sample {
    ImuInput input;
    int64_t arrival_ns;
  };
  struct CameraStream {
    StreamCounts counts;
    std::optional<int64_t> newest_ns;
  };
  struct ImuStream {
    StreamCounts counts;
    std::deque<Sample> samples;  // by time
  };
  struct Group {
    int64_t time_ns;
    std::vector<std::optional<CameraInput>> cameras;
    int64_t last_input_ns;
  };

  bool Active(const StreamCounts& counts, int64_t now_ns) const;
  bool Complete(const Group& group, int64_t now_ns) const;
  void ClockFromImus(int64_t now_ns);
  // Hands over the pending frames, oldest first, while each is complete, due or beyond the
  // queue's bound; all: every one.
  std::vector<SyncedFrame> TakePending(int64_t now_ns, bool all);
  SyncedFrame Release(Group group, int64_t now_ns);
  // The IMU's reading at t_ns (slerp / lerp), with the newest arrival of what it used.
  std::optional<std::pair<ImuObservation, int64_t>> Interpolate(int i, int64_t t_ns) const;

  SyncOptions options_;
  std::vector<CameraStream> cameras_;
  std::vector<ImuStream> imus_;
  std::deque<Group> pending_;  // by time
  std::optional<int64_t> last_released_ns_, epoch_ns_, first_arrival_ns_;
  uint64_t frames_released_ = 0, frames_forced_ = 0;
};

}  // namespace mocap

#endif  // MOCAP_STREAM_SYNC_H_
