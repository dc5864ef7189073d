// SubjectTracker: several people tracked across views (mocap/subject_tracker.h).
#include <pybind11/stl.h>

#include <tuple>

#include "bindings.h"
#include "mocap/subject_tracker.h"

namespace mocap::bindings {
namespace {

using Suit = std::tuple<Skeleton, KeypointLayout, std::vector<ImuSite>>;

std::unique_ptr<SubjectTracker> CreateTracker(Skeleton skeleton, Rig rig, KeypointLayout layout,
                                              std::optional<PosePrior> prior, SolverOptions options,
                                              TrackerOptions tracking,
                                              const std::vector<Suit>& suits) {
  std::string error;
  if (!Solver::Create(skeleton, rig, layout, {}, prior, options, &error))
    throw std::invalid_argument(error);
  auto make = [=] {
    std::string ignored;
    return Solver::Create(skeleton, rig, layout, {}, prior, options, &ignored);
  };
  std::vector<SuitCalibration> calibrations;
  for (const auto& [s, l, i] : suits) calibrations.push_back({s, l, i});
  return std::make_unique<SubjectTracker>(make, tracking, calibrations);
}

// keypoints (N, K, 3): the N people of the frame, people i seen by cameras[i]; per suit its
// sensors' quaternions (M, 4) and accelerations (M, 3), NaN where missing.
py::tuple Track(SubjectTracker& tracker, double timestamp, const std::vector<int>& cameras,
                Array keypoints, const std::vector<Array>& quaternions,
                const std::vector<Array>& accelerations) {
  const FrameObservations frame = MakeFrame(timestamp, cameras, keypoints, {}, Array(), Array());
  if (quaternions.size() != accelerations.size())
    throw std::invalid_argument("one quaternion and one acceleration array per suit");
  std::vector<std::vector<ImuObservation>> suits;
  for (size_t k = 0; k < quaternions.size(); ++k) {
    std::vector<int> sensors(quaternions[k].ndim() == 2 ? quaternions[k].shape(0) : 0);
    for (size_t i = 0; i < sensors.size(); ++i) sensors[i] = static_cast<int>(i);
    suits.push_back(
        MakeFrame(timestamp, {}, Array(), sensors, quaternions[k], accelerations[k]).imus);
  }
  std::vector<uint32_t> assigned;
  std::vector<SubjectFrame> subjects;
  {
    py::gil_scoped_release release;
    subjects = tracker.Track(timestamp, frame.cameras, &assigned, suits);
  }
  return py::make_tuple(subjects, assigned);
}

py::dict Counts(const SubjectTracker& tracker) {
  const TrackerCounts& c = tracker.counts();
  py::dict d;
  d["births"] = c.births, d["revivals"] = c.revivals, d["retired"] = c.retired;
  d["people_dropped"] = c.people_dropped, d["births_refused"] = c.births_refused;
  d["views_unexplained"] = c.views_unexplained, d["suit_changes"] = c.suit_changes;
  d["suits_doubted"] = c.suits_doubted;
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
      .def_readwrite("threads", &TrackerOptions::threads)
      .def_property(
          "suit_window_s", [](const TrackerOptions& o) { return o.suits.window_s; },
          [](TrackerOptions& o, double s) { o.suits.window_s = s; },
          "how much of the take a suit's agreement with a subject is measured over, s")
      .def_property(
          "suit_gate_rad", [](const TrackerOptions& o) { return o.suits.gate_rad; },
          [](TrackerOptions& o, double g) { o.suits.gate_rad = g; },
          "a suit disagreeing more than this with every subject is on nobody, rad")
      .def_property(
          "suit_margin_rad", [](const TrackerOptions& o) { return o.suits.margin_rad; },
          [](TrackerOptions& o, double m) { o.suits.margin_rad = m; },
          "a suit's wearer beats every alternative by this, rad")
      .def_property(
          "suit_lock_ratio", [](const TrackerOptions& o) { return o.suits.lock_ratio; },
          [](TrackerOptions& o, double r) { o.suits.lock_ratio = r; },
          "beyond the gate, a suit whose disagreement is below this fraction of chance (its turns "
          "shifted in time) is admitted");
}

}  // namespace

void BindTracker(py::module_& m) {
  BindTrackerOptions(m);
  py::class_<SubjectFrame>(m, "SubjectFrame")
      .def_readonly("id", &SubjectFrame::id)
      .def_readonly("result", &SubjectFrame::result)
      .def_readonly("cameras", &SubjectFrame::cameras)
      .def_readonly("born", &SubjectFrame::born)
      .def_readonly("suit", &SubjectFrame::suit)
      .def_readonly("skeleton", &SubjectFrame::skeleton);
  py::class_<SubjectTracker>(m, "SubjectTracker")
      .def(py::init(&CreateTracker), py::arg("skeleton"), py::arg("rig"), py::arg("layout"),
           py::arg("prior") = py::none(), py::arg("options") = SolverOptions(),
           py::arg("tracking") = TrackerOptions(), py::arg("suits") = std::vector<Suit>(),
           "suits: (skeleton, layout, IMU sites) of each suit that may be worn")
      .def("track", &Track, py::arg("timestamp"), py::arg("cameras"), py::arg("keypoints"),
           py::arg("suit_quaternions_wxyz") = std::vector<Array>(),
           py::arg("suit_accelerations") = std::vector<Array>(),
           "One frame's people: keypoints (N, K, 3) pixels+confidence, person i seen by "
           "cameras[i]; per suit (all or none) its readings, (M, 4) and (M, 3). Returns (every "
           "subject tracked, per person the id of its subject or 0).")
      .def_property_readonly("wearers", &SubjectTracker::wearers,
                             "per suit: the id of the subject wearing it, 0 for none")
      .def_property_readonly("counts", &Counts)
      .def_property_readonly("tracked", &SubjectTracker::tracked);
}

}  // namespace mocap::bindings
