// libFuzzer target: a Calibration message's content (calibration_queue.cc): the
// calibrator's skeleton, keypoint layout and IMU sites as JSON, checked against the
// fixture session's solver and, when taken, applied to a solver. Input: three pieces
// [u16 length][text] (skeleton, layout, IMU sites) and the rest as the source's name; the
// wire encoding itself is fuzzed by fuzz_wire. Checks: Add returns true or false with an
// error and never throws or crashes; what it queues the solver takes.
#include <cstdlib>

#include "calibration_queue.h"
#include "fuzz_support.h"
#include "solve_step.h"

namespace {

std::unique_ptr<mocap::Solver> FixtureSolver(std::string* error) {
  const mocap::Session& s = mocap::fuzz::FixtureSession();
  return mocap::Solver::Create(s.skeleton, s.rig, s.layout, s.imus, s.prior, s.solver, error);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::unique_ptr<mocap::Solver> checker = [] {
    std::string error;
    auto solver = FixtureSolver(&error);
    if (!solver) std::abort();
    return solver;
  }();
  mocap::fuzz::Reader in(data, size);
  mocap::v1::Calibration c;
  c.set_skeleton_json(std::string(in.Piece()));
  c.set_layout_json(std::string(in.Piece()));
  c.set_imus_json(std::string(in.Piece()));
  c.set_source(std::string(in.Rest()));
  c.set_sequence(1);
  mocap::CalibrationQueue queue;
  std::string error;
  const bool ok = queue.Add(c, *checker, &error);
  if (!ok && error.empty()) std::abort();
  for (const mocap::PendingCalibration& p : queue.TakeDue(c.valid_from_ns())) {
    std::string why;
    auto solver = FixtureSolver(&why);
    mocap::SolveStep step(std::move(solver), false);
    if (!step.Apply(p, &why)) std::abort();  // checked on arrival: the solver takes it
  }
  return 0;
}
