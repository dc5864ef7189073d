// SubjectTracker: several people tracked across views (mocap/subject_tracker.h).
#include <pybind11/stl.h>

#include "bindings.h"
#include "mocap/subject_tracker.h"

namespace mocap::bindings {
namespace {

std::unique_ptr<SubjectTracker> CreateTracker(Skeleton skeleton, Rig rig, KeypointLayout layout,
                                              std::optional<PosePrior> prior, SolverOptions options,
                                              TrackerOptions tracking) {
  std::string error;
  if (!Solver::Create(skeleton, rig, layout, {}, prior, options, &error))
    throw std::invalid_argument(error);
  auto make = [=] {
    std::string ignored;
    return Solver::Create(skeleton, rig, layout, {}, prior, options, &ignored);
  };
  return std::make_unique<SubjectTracker>(make, tracking);
}

// keypoints (N, K, 3): the N people of the frame, people i seen by cameras[i].
py::tuple Track(SubjectTracker& tracker, double timestamp, const std::vector<int>& cameras,
                Array keypoints) {
  const FrameObservations frame = MakeFrame(timestamp, cameras, keypoints, {}, Array(), Array());
  std::vector<uint32_t> assigned;
  std::vector<SubjectFrame> subjects;
  {
    py::gil_scoped_release release;
    subjects = tracker.Track(timestamp, frame.cameras, &assigned);
  }
  return py::make_tuple(subjects, assigned);
}

py::dict Counts(const SubjectTracker& tracker) {
  const TrackerCounts& c = tracker.counts();
  py::dict d;
  d["births"] = c.births, d["revivals"] = c.revivals, d["retired"] = c.retired;
  d["people_dropped"] = c.people_dropped, d["births_refused"] = c.births_refused;
  d["views_unexplained"] = c.views_unexplained;
  return d;
}

void BindTrackerOptions(py::module_& m) {
  py::class_<TrackerOptions>(m, "TrackerOptions")
      .def(py::init<>())
      .def_readwrite("gate", &TrackerOptions::gate)
      .def_readwrite("birth_frames", &TrackerOptions::birth_frames)
      .def_readwrite("birth_radius_m", &TrackerOptions::birth_radius_m)
      .def_readwrite("revive_radius_m", &TrackerOptions::revive_radius_m)
      .def_readwrite("retire_s", &TrackerOptions::retire_s)
      .def_readwrite("max_people_per_camera", &TrackerOptions::max_people_per_camera)
      .def_readwrite("max_subjects", &TrackerOptions::max_subjects)
      .def_readwrite("min_keypoints", &TrackerOptions::min_keypoints)
      .def_readwrite("min_confidence", &TrackerOptions::min_confidence)
      .def_readwrite("threads", &TrackerOptions::threads);
}

}  // namespace

void BindTracker(py::module_& m) {
  BindTrackerOptions(m);
  py::class_<SubjectFrame>(m, "SubjectFrame")
      .def_readonly("id", &SubjectFrame::id)
      .def_readonly("result", &SubjectFrame::result)
      .def_readonly("cameras", &SubjectFrame::cameras)
      .def_readonly("born", &SubjectFrame::born);
  py::class_<SubjectTracker>(m, "SubjectTracker")
      .def(py::init(&CreateTracker), py::arg("skeleton"), py::arg("rig"), py::arg("layout"),
           py::arg("prior") = py::none(), py::arg("options") = SolverOptions(),
           py::arg("tracking") = TrackerOptions())
      .def("track", &Track, py::arg("timestamp"), py::arg("cameras"), py::arg("keypoints"),
           "One frame's people: keypoints (N, K, 3) pixels+confidence, person i seen by "
           "cameras[i]. Returns (every subject tracked, per person the id of its subject or 0).")
      .def_property_readonly("counts", &Counts)
      .def_property_readonly("tracked", &SubjectTracker::tracked);
}

}  // namespace mocap::bindings
