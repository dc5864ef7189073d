// The pieces the binding files share (module mocap._core, bindings.cc): the numpy array
// type, error conversion, the frame conversion, and one Bind function per area.
#ifndef MOCAP_PYTHON_BINDINGS_H_
#define MOCAP_PYTHON_BINDINGS_H_

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "mocap/observations.h"

namespace mocap::bindings {

namespace py = pybind11;

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

// Runs load(&value, &error); throws ValueError with the error when it fails.
template <typename T, typename Load>
T Checked(Load load) {
  T value;
  std::string error;
  if (!load(&value, &error)) throw std::invalid_argument(error);
  return value;
}

// keypoints: (C, K, 3) [x, y, confidence] for the cameras listed; quaternions (M, 4) w, x, y,
// z; accelerations (M, 3). NaN marks a missing orientation or acceleration.
FrameObservations MakeFrame(double timestamp, const std::vector<int>& cameras, Array keypoints,
                            const std::vector<int>& imus, Array quaternions, Array accelerations);

void BindGeometry(py::module_& m);     // SO(3), Skeleton, fit_to_points
void BindSites(py::module_& m);        // KeypointLayout, ImuSite and their files, the floor
void BindCamera(py::module_& m);       // Camera, Rig
void BindOptions(py::module_& m);      // LossType, Term-, Solver-, Sync-, CalibrationOptions
void BindSolver(py::module_& m);       // PosePrior, SolveResult, Solver
void BindCalibration(py::module_& m);  // CalibrationResult, calibrate_window
void BindPipeline(py::module_& m);     // HostPipeline
void BindInput(py::module_& m);        // InputPath, SyncedFrame
void BindTracker(py::module_& m);      // TrackerOptions, SubjectFrame, SubjectTracker

}  // namespace mocap::bindings

#endif  // MOCAP_PYTHON_BINDINGS_H_
