#include "solve_step.h"

#include <algorithm>

namespace mocap {

SolveStep::SolveStep(std::unique_ptr<Solver> solver, bool imus_calibrated)
    : solver_(std::move(solver)), imus_calibrated_(solver_->imus().size(), imus_calibrated) {}

SolveResult SolveStep::Solve(FrameObservations* frame) {
  std::vector<ImuObservation>& imus = frame->imus;
  imus.erase(std::remove_if(imus.begin(), imus.end(),
                            [&](const ImuObservation& i) { return !imus_calibrated_[i.imu]; }),
             imus.end());
  return solver_->Solve(*frame);
}

bool SolveStep::Apply(const PendingCalibration& c, std::string* error) {
  if (!solver_->SetCalibration(c.skeleton, c.layout, c.imus, error)) return false;
  imus_calibrated_ = c.calibrated;
  return true;
}

bool SolveStep::any_imu_calibrated() const {
  return std::find(imus_calibrated_.begin(), imus_calibrated_.end(), true) !=
         imus_calibrated_.end();
}

}  // namespace mocap
