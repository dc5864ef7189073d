// The solve of synchronised frames with the calibration in use. IMUs whose mounting and
// heading are not known yet (a session started before its calibration) are synchronised
// but left out of the solve until a calibration brings them.
#ifndef MOCAP_DAEMON_SOLVE_STEP_H_
#define MOCAP_DAEMON_SOLVE_STEP_H_

#include <memory>
#include <string>
#include <vector>

#include "calibration_queue.h"
#include "mocap/solver.h"

namespace mocap {

class SolveStep {
 public:
  // imus_calibrated: whether the solver's IMU sites are calibrated (all or none).
  SolveStep(std::unique_ptr<Solver> solver, bool imus_calibrated);

  // Solves a frame with its calibrated IMUs; the others are removed from *frame, which so
  // lists what the solve used.
  SolveResult Solve(FrameObservations* frame);

  // Puts a calibration in use from the next frame on, its IMUs calibrated, the others not.
  // False with *error, nothing changed, when the solver refuses it.
  bool Apply(const PendingCalibration& calibration, std::string* error);

  const Solver& solver() const { return *solver_; }
  // Per IMU of the solver: solved with.
  const std::vector<bool>& imus_calibrated() const { return imus_calibrated_; }
  bool any_imu_calibrated() const;

 private:
  std::unique_ptr<Solver> solver_;
  std::vector<bool> imus_calibrated_;
};

}  // namespace mocap

#endif  // MOCAP_DAEMON_SOLVE_STEP_H_
