// The per-frame solve: the PCA prior, the solver and its result.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "mocap/prior.h"
#include "mocap/solver.h"

namespace mocap::bindings {
namespace {

void BindPrior(py::module_& m) {
  py::class_<PosePrior>(m, "PosePrior")
      .def(py::init([](Eigen::VectorXd mean, Eigen::MatrixXd basis, Eigen::VectorXd sigma) {
             return Checked<PosePrior>([&](PosePrior* p, std::string* e) {
               *p = PosePrior{std::move(mean), std::move(basis), std::move(sigma)};
               return p->IsValid(e);
             });
           }),
           py::arg("mean"), py::arg("basis"), py::arg("sigma"))
      .def_static("load",
                  [](const std::string& path) {
                    return Checked<PosePrior>([&](PosePrior* out, std::string* e) {
                      return LoadPosePriorJson(path, out, e);
                    });
                  })
      .def("to_json", &PosePriorToJson)
      .def_readonly("mean", &PosePrior::mean)
      .def_readonly("basis", &PosePrior::basis)
      .def_readonly("sigma", &PosePrior::sigma);
}

py::dict Counts(const SolveResult& r) {
  const InputCounts& c = r.counts;
  return py::dict(py::arg("keypoints_used") = c.keypoints_used,
                  py::arg("keypoints_not_detected") = c.keypoints_not_detected,
                  py::arg("keypoints_invalid") = c.keypoints_invalid,
                  py::arg("keypoints_behind_camera") = c.keypoints_behind_camera,
                  py::arg("orientations_used") = c.orientations_used,
                  py::arg("orientations_invalid") = c.orientations_invalid,
                  py::arg("orientations_distrusted") = c.orientations_distrusted,
                  py::arg("accelerations_used") = c.accelerations_used,
                  py::arg("accelerations_invalid") = c.accelerations_invalid,
                  py::arg("unknown_sources") = c.unknown_sources);
}

py::dict Costs(const SolveResult& r) {
  const TermCosts& c = r.costs;
  return py::dict(py::arg("orientation") = c.orientation, py::arg("position") = c.position,
                  py::arg("acceleration") = c.acceleration,
                  py::arg("pca_projection") = c.pca_projection,
                  py::arg("pca_deviation") = c.pca_deviation, py::arg("motion") = c.motion,
                  py::arg("ground") = c.ground);
}

py::dict Timings(const SolveResult& r) {
  const SolveTimings& t = r.timings;
  return py::dict(py::arg("total") = t.total, py::arg("linear_solver") = t.linear_solver,
                  py::arg("jacobian_evaluation") = t.jacobian_evaluation,
                  py::arg("residual_evaluation") = t.residual_evaluation);
}

void BindResult(py::module_& m) {
  const auto flag = [](int bit) {
    return [bit](const SolveResult& r) { return bool(r.flags & bit); };
  };
  py::class_<SolveResult>(m, "SolveResult")
      .def_property_readonly("status",
                             [](const SolveResult& r) { return std::string(ToString(r.status)); })
      .def_readonly("theta", &SolveResult::theta)
      .def_readonly("timestamp", &SolveResult::timestamp)
      .def_readonly("iterations", &SolveResult::iterations)
      .def_readonly("solve_time_ms", &SolveResult::solve_time_ms)
      .def_readonly("message", &SolveResult::message)
      .def_readonly("imus_distrusted", &SolveResult::imus_distrusted,
                    "IMU sites left out of this solve: the keypoints contradict them")
      .def_property_readonly("timings_ms", &Timings)
      .def_property_readonly("position_unconstrained", flag(kPositionUnconstrained))
      .def_property_readonly("iteration_limit", flag(kIterationLimit))
      .def_property_readonly("lost_and_reacquired", flag(kLostAndReacquired))
      .def_property_readonly("reinitialised", flag(kReinitialised))
      .def_property_readonly("costs", &Costs)
      .def_property_readonly("counts", &Counts);
}

std::unique_ptr<Solver> CreateSolver(Skeleton s, Rig r, KeypointLayout l, std::vector<ImuSite> i,
                                     std::optional<PosePrior> p, SolverOptions o) {
  std::string e;
  auto solver =
      Solver::Create(std::move(s), std::move(r), std::move(l), std::move(i), std::move(p), o, &e);
  if (!solver) throw std::invalid_argument(e);
  return solver;
}

SolveResult SolveFrame(Solver& s, double t, const std::vector<int>& cameras, Array keypoints,
                       const std::vector<int>& imus, Array quaternions, Array accelerations) {
  const FrameObservations f = MakeFrame(t, cameras, keypoints, imus, quaternions, accelerations);
  py::gil_scoped_release release;
  return s.Solve(f);
}

void SetOptions(Solver& s, const SolverOptions& o) {
  std::string e;
  if (!s.SetOptions(o, &e)) throw std::invalid_argument(e);
}

}  // namespace

void BindSolver(py::module_& m) {
  BindPrior(m);
  BindResult(m);
  py::class_<Solver>(m, "Solver")
      .def(py::init(&CreateSolver), py::arg("skeleton"), py::arg("rig"), py::arg("layout"),
           py::arg("imus"), py::arg("prior") = py::none(), py::arg("options") = SolverOptions())
      .def("solve", &SolveFrame, py::arg("timestamp"), py::arg("cameras"), py::arg("keypoints"),
           py::arg("imus"), py::arg("quaternions_wxyz"), py::arg("accelerations"),
           "Solve one frame. keypoints (C, K, 3) pixels+confidence for the listed cameras; "
           "quaternions (M, 4) sensor->IMU reference, w first; accelerations (M, 3) m/s^2 in the "
           "sensor frame with gravity. NaN marks a missing reading.")
      .def("reset", &Solver::Reset)
      .def_property(
          "options", [](const Solver& s) { return SolverOptions(s.options()); },  // a copy
          &SetOptions, "Replace the options from the next frame on (ValueError when out of range).")
      .def("set_warm_start", &Solver::SetWarmStart)
      .def_property_readonly("pose", &Solver::pose)
      .def_property_readonly("headings", &Solver::headings,
                             "heading corrections psi_i (rad about world z), one per IMU site")
      .def_property_readonly("initialised", &Solver::initialised);
}

}  // namespace mocap::bindings
