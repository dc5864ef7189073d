// The host's input path (host/daemon/input_path.h): wire messages into synchronised frames,
// the frames mocapd solves, for the Python tools that read a recording or the live streams.
// A SyncedFrame's attributes are the Solver's inputs: solver.solve(f.timestamp, f.cameras,
// f.keypoints, f.imus, f.quaternions_wxyz, f.accelerations) solves the frame mocapd would.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <cmath>

#include "bindings.h"
#include "input_path.h"
#include "session.h"

namespace mocap::bindings {
namespace {

std::vector<int> Cameras(const SyncedFrame& f) {
  std::vector<int> cameras;
  for (const CameraObservation& o : f.observations.cameras) cameras.push_back(o.camera);
  return cameras;
}

// (C, K, 3) x, y, confidence of the subject in each camera of Cameras(f).
py::array_t<double> Keypoints(const SyncedFrame& f) {
  const auto& cameras = f.observations.cameras;
  const size_t k = cameras.empty() ? 0 : cameras[0].keypoints.size();
  py::array_t<double> out({cameras.size(), k, size_t{3}});
  auto a = out.mutable_unchecked<3>();
  for (size_t c = 0; c < cameras.size(); ++c) {
    for (size_t i = 0; i < k; ++i) {
      const Keypoint2D& p = cameras[c].keypoints[i];
      a(c, i, 0) = p.x, a(c, i, 1) = p.y, a(c, i, 2) = p.confidence;
    }
  }
  return out;
}

std::vector<int> Imus(const SyncedFrame& f) {
  std::vector<int> imus;
  for (const ImuObservation& o : f.observations.imus) imus.push_back(o.imu);
  return imus;
}

// (M, 4) w, x, y, z of each reading of Imus(f); NaN where it has no orientation.
Eigen::MatrixX4d Quaternions(const SyncedFrame& f) {
  const auto& imus = f.observations.imus;
  Eigen::MatrixX4d out(imus.size(), 4);
  for (size_t i = 0; i < imus.size(); ++i) {
    const Eigen::Quaterniond& q = imus[i].orientation;
    out.row(i) = imus[i].has_orientation ? Eigen::RowVector4d(q.w(), q.x(), q.y(), q.z())
                                         : Eigen::RowVector4d::Constant(NAN);
  }
  return out;
}

// (M, 3) m/s^2 of each reading of Imus(f); NaN where it has no acceleration.
Eigen::MatrixX3d Accelerations(const SyncedFrame& f) {
  const auto& imus = f.observations.imus;
  Eigen::MatrixX3d out(imus.size(), 3);
  for (size_t i = 0; i < imus.size(); ++i) {
    out.row(i) = imus[i].has_acceleration ? Eigen::RowVector3d(imus[i].acceleration.transpose())
                                          : Eigen::RowVector3d::Constant(NAN);
  }
  return out;
}

// Per reading of Imus(f): whether it has an orientation / an acceleration.
auto Flags(bool ImuObservation::*flag) {
  return [flag](const SyncedFrame& f) {
    std::vector<bool> out;
    for (const ImuObservation& o : f.observations.imus) out.push_back(o.*flag);
    return out;
  };
}

void BindSyncedFrame(py::module_& m) {
  py::class_<SyncedFrame>(m, "SyncedFrame")
      .def_readonly("time_ns", &SyncedFrame::time_ns, "capture time, shared timebase")
      .def_property_readonly(
          "timestamp", [](const SyncedFrame& f) { return f.observations.timestamp; },
          "seconds since the input path's first released frame (the solver's clock)")
      .def_readonly("last_input_ns", &SyncedFrame::last_input_ns)
      .def_readonly("released_ns", &SyncedFrame::released_ns)
      .def_readonly("cameras_clocked", &SyncedFrame::cameras_clocked,
                    "cameras that delivered the frame, detected or not")
      .def_readonly("cameras_detected", &SyncedFrame::cameras_detected,
                    "of those, the ones that ran detection on it")
      .def_property_readonly("cameras", &Cameras, "cameras with the subject's keypoints")
      .def_property_readonly("keypoints", &Keypoints, "(C, K, 3) x, y, confidence per camera")
      .def_property_readonly("imus", &Imus, "IMUs with a reading at the frame's time")
      .def_property_readonly("quaternions_wxyz", &Quaternions, "(M, 4); NaN: no orientation")
      .def_property_readonly("accelerations", &Accelerations, "(M, 3) m/s^2; NaN: none")
      .def_property_readonly("has_orientation", Flags(&ImuObservation::has_orientation))
      .def_property_readonly("has_acceleration", Flags(&ImuObservation::has_acceleration));
}

std::unique_ptr<InputPath> CreatePath(const Rig& rig, const std::vector<ImuSite>& imus,
                                      const KeypointLayout& layout, const SyncOptions& sync,
                                      double min_confidence) {
  std::string error;
  if (!sync.IsValid(&error)) throw std::invalid_argument(error);
  if (!(min_confidence >= 0 && min_confidence < 1))
    throw std::invalid_argument("min_confidence must be in [0, 1)");
  return std::make_unique<InputPath>(rig, imus, layout, sync, min_confidence);
}

// The input path of a session file, read by mocapd's reader.
std::unique_ptr<InputPath> FromSession(const std::string& session_path) {
  Session s;
  std::string error;
  if (!LoadSession(session_path, &s, &error)) throw std::invalid_argument(error);
  return std::make_unique<InputPath>(s.rig, s.imus, s.layout, s.sync, s.solver.min_confidence);
}

py::tuple Feed(InputPath& p, const std::string& type, py::bytes payload, int64_t now_ns,
               const Solver* tracker) {
  std::string why;
  const bool ok = p.Feed(type, std::string(payload), now_ns, tracker, &why);
  return py::make_tuple(ok, why);
}

py::dict Counts(const StreamCounts& c) {
  return py::dict(py::arg("received") = c.received, py::arg("late") = c.late,
                  py::arg("duplicates") = c.duplicates, py::arg("out_of_order") = c.out_of_order);
}

py::list CameraCounts(const InputPath& p) {
  py::list out;
  for (int c = 0; c < p.sync().num_cameras(); ++c) out.append(Counts(p.sync().camera_counts(c)));
  return out;
}

py::list ImuCounts(const InputPath& p) {
  py::list out;
  for (int i = 0; i < p.sync().num_imus(); ++i) out.append(Counts(p.sync().imu_counts(i)));
  return out;
}

void BindInputPath(py::module_& m) {
  py::class_<InputPath>(m, "InputPath")
      .def(py::init(&CreatePath), py::arg("rig"), py::arg("imus"), py::arg("layout"),
           py::arg("sync") = SyncOptions(), py::arg("min_confidence") = 0.05,
           "Checks, maps and synchronises wire messages as mocapd does (ValueError when the "
           "sync options are out of range).")
      .def_static("from_session", &FromSession, py::arg("session_path"),
                  "The input path of a session file as mocapd reads it: its rig, IMU set, "
                  "layout, sync and the solver's min_confidence (ValueError when it is wrong).")
      .def("feed", &Feed, py::arg("type_name"), py::arg("payload"), py::arg("now_ns"),
           py::arg("tracker") = py::none(),
           "One message received at now_ns (arrival clock); tracker: a Solver whose pose, once "
           "initialised, picks the subject among several persons. (accepted, 'reason: detail').")
      .def("take_ready", &InputPath::TakeReady, py::arg("now_ns"),
           py::call_guard<py::gil_scoped_release>(), "Frames ready at now_ns, oldest first.")
      .def("flush", &InputPath::Flush, py::call_guard<py::gil_scoped_release>(),
           "The end of the input: every frame still pending, released max_wait after the "
           "newest arrival.")
      .def_property_readonly("layout_name",
                             [](const InputPath& p) { return p.decoder().layout_name(); })
      .def_property_readonly(
          "keypoints", [](const InputPath& p) { return p.decoder().layout_size(); },
          "keypoints per person of the layout")
      .def_property_readonly(
          "dropped", [](const InputPath& p) { return p.monitor().dropped(); },
          "messages (IMU samples) dropped, by reason")
      .def_property_readonly("camera_counts", &CameraCounts,
                             "per camera of the rig: received, late, duplicates, out_of_order")
      .def_property_readonly("imu_counts", &ImuCounts,
                             "per IMU of the set: received, late, duplicates, out_of_order");
}

}  // namespace

void BindInput(py::module_& m) {
  BindSyncedFrame(m);
  BindInputPath(m);
}

}  // namespace mocap::bindings
