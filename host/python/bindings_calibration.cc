// The window calibration: bone lengths, keypoint sites, IMU mountings and headings over a
// window of frames (mocap/window_calibration.h).
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "mocap/window_calibration.h"

namespace mocap::bindings {
namespace {

void BindResult(py::module_& m) {
  py::class_<CalibrationResult>(m, "CalibrationResult")
      .def_readonly("skeleton", &CalibrationResult::skeleton)
      .def_readonly("layout", &CalibrationResult::layout)
      .def_readonly("imus", &CalibrationResult::imus)
      .def_readonly("scales", &CalibrationResult::scales)
      .def_readonly("shifts", &CalibrationResult::shifts)
      .def_readonly("thetas", &CalibrationResult::thetas)
      .def_readonly("imu_residual_deg", &CalibrationResult::imu_residual_deg)
      .def_readonly("keypoint_observations", &CalibrationResult::keypoint_observations)
      .def_readonly("site_directions_kept", &CalibrationResult::site_directions_kept)
      .def_readonly("site_directions", &CalibrationResult::site_directions)
      .def_readonly("initial_cost", &CalibrationResult::initial_cost)
      .def_readonly("final_cost", &CalibrationResult::final_cost)
      .def_readonly("iterations", &CalibrationResult::iterations)
      .def_readonly("converged", &CalibrationResult::converged)
      .def_readonly("message", &CalibrationResult::message);
}

// frames: [(time, cameras, keypoints, imus, quaternions, accelerations)] as Solver.solve
// takes them.
std::vector<FrameObservations> Frames(const py::list& frames) {
  std::vector<FrameObservations> obs;
  for (const py::handle& f : frames) {
    const auto t = f.cast<py::tuple>();
    if (t.size() != 6)
      throw std::invalid_argument(
          "a frame is (time, cameras, keypoints, imus, quaternions, accelerations)");
    obs.push_back(MakeFrame(t[0].cast<double>(), t[1].cast<std::vector<int>>(), t[2].cast<Array>(),
                            t[3].cast<std::vector<int>>(), t[4].cast<Array>(), t[5].cast<Array>()));
  }
  return obs;
}

CalibrationResult Calibrate(const Skeleton& s, const Rig& r, const KeypointLayout& l,
                            const std::vector<ImuSite>& i, std::optional<PosePrior> p,
                            const py::list& frames, const std::vector<Eigen::VectorXd>& thetas,
                            const CalibrationOptions& o) {
  const std::vector<FrameObservations> obs = Frames(frames);
  CalibrationResult result;
  std::string e;
  bool ok;
  {
    py::gil_scoped_release release;
    ok = CalibrateWindow(s, r, l, i, p, obs, thetas, o, &result, &e);
  }
  if (!ok) throw std::invalid_argument(e);
  return result;
}

}  // namespace

void BindCalibration(py::module_& m) {
  BindResult(m);
  m.def("calibrate_window", &Calibrate, py::arg("skeleton"), py::arg("rig"), py::arg("layout"),
        py::arg("imus"), py::arg("prior"), py::arg("frames"), py::arg("thetas"),
        py::arg("options") = CalibrationOptions(),
        "Bone lengths, keypoint sites, IMU mountings and headings over a window of frames "
        "(window_calibration.h). frames: [(time, cameras, keypoints, imus, quaternions, "
        "accelerations)] as Solver.solve takes them; thetas: the frames' starting poses.");
}

}  // namespace mocap::bindings
