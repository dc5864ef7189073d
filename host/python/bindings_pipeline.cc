// The live host's pipeline without the transport (host/daemon/pipeline.h): an offline solve
// of a recording feeds it the recorded messages with their arrival times.
#include <pybind11/stl.h>

#include "bindings.h"
#include "pipeline.h"

namespace mocap::bindings {
namespace {

std::unique_ptr<HostPipeline> Load(const std::string& session_path) {
  Session session;
  std::string e;
  if (!LoadSession(session_path, &session, &e)) throw std::invalid_argument(e);
  auto p = HostPipeline::Create(std::move(session), &e);
  if (!p) throw std::invalid_argument(e);
  return p;
}

py::tuple Feed(HostPipeline& p, py::bytes type, py::bytes payload, int64_t now_ns) {
  std::string why;
  const bool ok = p.Feed(std::string(type), std::string(payload), now_ns, &why);
  return py::make_tuple(ok, why);
}

py::list Encoded(const std::vector<SolvedFrame>& frames) {
  py::list out;
  for (const SolvedFrame& f : frames)
    out.append(py::make_tuple(py::bytes(f.pose.SerializeAsString()), f.last_input_ns));
  return out;
}

py::list Solve(HostPipeline& p, int64_t now_ns) {
  std::vector<SolvedFrame> frames;
  {
    py::gil_scoped_release release;
    frames = p.Solve(now_ns);
  }
  return Encoded(frames);
}

py::list Flush(HostPipeline& p) {
  std::vector<SolvedFrame> frames;
  {
    py::gil_scoped_release release;
    frames = p.Flush();
  }
  return Encoded(frames);
}

}  // namespace

void BindPipeline(py::module_& m) {
  py::class_<HostPipeline>(m, "HostPipeline")
      .def_static("load", &Load, py::arg("session_path"),
                  "A pipeline from a session file (ValueError when it is wrong).")
      .def("feed", &Feed, py::arg("type"), py::arg("payload"), py::arg("now_ns"),
           "Feed one message; (accepted, why it was dropped).")
      .def("solve", &Solve, py::arg("now_ns"),
           "Frames ready at now_ns: [(PoseFrame bytes, last input arrival ns)].")
      .def("flush", &Flush, "The end of the input: every frame still pending, solved (as solve()).")
      .def("health", [](HostPipeline& p,
                        int64_t now_ns) { return py::bytes(p.Health(now_ns).SerializeAsString()); })
      .def_property_readonly("dropped", &HostPipeline::dropped)
      .def_property_readonly(
          "skeleton", [](const HostPipeline& p) { return p.session().skeleton; },
          "the skeleton in use: the session's, or the latest calibration's")
      .def_property_readonly("headings", &HostPipeline::headings,
                             "the solver's heading corrections (rad, per IMU of the session)")
      .def_property_readonly("calibrations_applied", &HostPipeline::calibrations_applied)
      .def_property_readonly("frames_solved", &HostPipeline::frames_solved);
}

}  // namespace mocap::bindings
