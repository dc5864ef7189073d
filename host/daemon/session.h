// The host's session file: what the daemon solves and where the streams are.
//   {"format": "mocap.session/1",
//    "skeleton": path, "rig": path, "layout": path, "imus": path, "prior": path or null,
//    "inputs": ["tcp://edge-box-1:5600", ...],   // every edge box and IMU hub (PUB, bound there)
//    "output": "tcp://*:5700",                  // where PoseFrame and Health are published
//    "sync": {"group_tolerance_ms": 4, "max_wait_ms": 25, "stale_after_ms": 300,
//             "imu_max_gap_ms": 40, "imu_max_hold_ms": 15, "imu_history_ms": 1000,
//             "imu_only_rate_hz": 60},
//    "solver": {"max_iterations": 10, "velocity_gain": 0.3, "heading_time_constant": 1,
//               "position": {"weight": 0.04, "loss": "cauchy"}, ...},
//    "imus_calibrated": true,
//    "curve": {"host_key": "keys/host.key", "inputs": {"tcp://edge-box-1:5600": "Z85 key"}},
//    "people": 1,
//    "suits": [{"imus": "suit_a.json", "skeleton": "performer_a.json"}, ...]}
// Paths are relative to the session file. "solver" takes every field of SolverOptions by its
// name, "sync" every field of SyncOptions but max_pending_frames, times in milliseconds
// (options_json.h: SolverOptionKeys, SyncOptionKeys). "imus_calibrated": false (default true) says
// the IMU set's mountings and headings are not known yet: the IMUs are synchronised but not solved
// with until a Calibration message (proto/mocap/v1/calibration.proto) brings them. Camera ids on
// the wire are the rig's camera names, sensor ids the IMU set's names. Missing "sync" / "solver"
// keys keep the defaults; an unknown key anywhere is an error naming it. "curve" (optional) holds
// the streams' keys (curve_keys.h); without it the streams are neither authenticated nor encrypted.
// "people" (default 1): the most performers solved at once. Above 1 every person of every camera
// is tracked (SubjectTracker: subject_tracker.h) and solved from video with the session's
// skeleton and layout, one PoseFrame per person with its subject_id. "suits" (several people
// only): the suits that may be worn, each an IMU set (every sensor one of "imus", in one suit
// only) calibrated on its wearer's skeleton (default the session's); which person wears which
// is found from motion, and the wearer solved with it. Without suits the IMUs are unused.
#ifndef MOCAP_DAEMON_SESSION_H_
#define MOCAP_DAEMON_SESSION_H_

#include <optional>
#include <string>
#include <vector>

#include "curve_keys.h"
#include "mocap/solver.h"
#include "mocap/stream_sync.h"
#include "mocap/subject_tracker.h"

namespace mocap {

// A suit of a session of several people: its calibration (skeleton, the session's layout on it,
// the suit's IMU sites) and, per suit IMU, its index in the session's IMU set.
struct Suit {
  SuitCalibration calibration;
  std::vector<int> sensors;
};

struct Session {
  Skeleton skeleton;
  Rig rig;
  KeypointLayout layout;  // scaled to the skeleton
  std::vector<ImuSite> imus;
  std::optional<PosePrior> prior;
  SolverOptions solver;
  SyncOptions sync;
  std::vector<std::string> inputs;
  std::string output;
  bool imus_calibrated = true;
  std::optional<CurveKeys> curve;
  int people = 1;
  std::vector<Suit> suits;
};

constexpr int kMaxPeople = 8;  // a session's "people"

bool LoadSession(const std::string& path, Session* out, std::string* error);

}  // namespace mocap

#endif  // MOCAP_DAEMON_SESSION_H_
