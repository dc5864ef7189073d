// Calibrations on their way to the solve. A Calibration message (a calibrator's skeleton,
// keypoint sites and IMU mountings) is checked when it arrives and applies from the first
// frame captured at or after its valid_from_ns, so a calibration estimated from a window of
// the take is used from a known frame on, whatever the transport delay.
#ifndef MOCAP_DAEMON_CALIBRATION_QUEUE_H_
#define MOCAP_DAEMON_CALIBRATION_QUEUE_H_

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "mocap/solver.h"
#include "mocap/v1/calibration.pb.h"

namespace mocap {

struct PendingCalibration {
  int64_t valid_from_ns = 0;
  Skeleton skeleton;
  KeypointLayout layout;         // scaled to the skeleton
  std::vector<ImuSite> imus;     // the session's IMU set, in its order
  std::vector<bool> calibrated;  // per IMU: brought by this calibration (others stay unused)
};

struct CalibrationCounts {
  uint64_t applied = 0;   // since the start
  uint64_t rejected = 0;  // did not fit the session (on arrival or when applied)
  uint64_t repeated = 0;  // a calibration taken before, sent again
};

class CalibrationQueue {
 public:
  // Checks a calibration against what `solver` solves with (Solver::CheckCalibration, the
  // session's layout and IMU set) and queues it: true. A source's calibration whose sequence
  // is not above the newest taken from it is a repeat (a calibrator repeats its latest for
  // hosts that start later): true, not queued. False with *error when it does not fit.
  bool Add(const v1::Calibration& calibration, const Solver& solver, std::string* error);

  // The queued calibrations valid at or before time_ns, oldest first, out of the queue.
  std::vector<PendingCalibration> TakeDue(int64_t time_ns);

  // The caller applied a calibration TakeDue gave (ok) or the solver refused it.
  void CountApplied(bool ok) { ok ? counts_.applied++ : counts_.rejected++; }

  const CalibrationCounts& counts() const { return counts_; }
  size_t size() const { return pending_.size(); }

 private:
  // Parses the calibration's files and maps its IMUs onto the solver's IMU set.
  bool Parse(const v1::Calibration& calibration, const Solver& solver, PendingCalibration* out,
             std::string* error) const;

  std::vector<PendingCalibration> pending_;    // by valid_from_ns
  std::map<std::string, uint64_t> sequences_;  // by source: the newest taken
  CalibrationCounts counts_;
};

}  // namespace mocap

#endif  // MOCAP_DAEMON_CALIBRATION_QUEUE_H_
