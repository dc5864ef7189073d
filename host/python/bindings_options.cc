// The options structs, derived from the fields each declares once (VisitFields, see
// mocap/solver_options.h): one attribute per field, and FIELDS, the field names in order,
// which tests compare with the session reader's keys and the Python wrapper.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "mocap/solver_options.h"
#include "mocap/stream_sync.h"
#include "mocap/window_calibration.h"
#include "options_json.h"

namespace mocap::bindings {
namespace {

template <typename Options>
py::class_<Options> BindFields(py::module_& m, const char* name) {
  py::class_<Options> c(m, name);
  c.def(py::init<>());
  std::vector<std::string> fields;
  Options::VisitFields([&](const char* field, auto member) {
    c.def_readwrite(field, member);
    fields.push_back(field);
  });
  c.attr("FIELDS") = py::tuple(py::cast(fields));
  return c;
}

// Raises ValueError with the conditions an options struct fails.
template <typename Options>
void Check(const Options& options) {
  std::string error;
  if (!options.IsValid(&error)) throw std::invalid_argument(error);
}

void BindSolverOptions(py::module_& m) {
  py::enum_<LossType>(m, "LossType")
      .value("TRIVIAL", LossType::kTrivial)
      .value("CAUCHY", LossType::kCauchy)
      .value("HUBER", LossType::kHuber);
  BindFields<TermOptions>(m, "TermOptions");
  BindFields<SolverOptions>(m, "SolverOptions")
      .def("check", &Check<SolverOptions>,
           "Raises ValueError naming every field out of range (one message per condition).")
      .def("to_session_json", &SolverOptionsToJson,
           "Every field as the session file's \"solver\" object (JSON text).")
      .def_static(
          "from_session_json",
          [](const std::string& text) {
            return Checked<SolverOptions>([&](SolverOptions* o, std::string* e) {
              return ParseSolverOptionsJson(text, o, e);
            });
          },
          py::arg("text"),
          "Options from a session's \"solver\" object, as mocapd reads it (ValueError naming an "
          "unknown key, a value of the wrong type or a field out of range).");
  m.def("session_solver_keys", &SolverOptionKeys,
        "Every key the session reader accepts in \"solver\" (a term's fields as term.field).");
}

void BindSyncOptions(py::module_& m) {
  BindFields<SyncOptions>(m, "SyncOptions")
      .def("check", &Check<SyncOptions>, "Raises ValueError when a field is out of range.")
      .def_static(
          "from_session_json",
          [](const std::string& text) {
            return Checked<SyncOptions>(
                [&](SyncOptions* o, std::string* e) { return ParseSyncOptionsJson(text, o, e); });
          },
          py::arg("text"),
          "Options from a session's \"sync\" object (times in ms), as mocapd reads it "
          "(ValueError naming an unknown key or a value that is not a number, or out of range).");
  m.def("session_sync_keys", &SyncOptionKeys, "Every key the session reader accepts in \"sync\".");
}

}  // namespace

void BindOptions(py::module_& m) {
  BindSolverOptions(m);
  BindSyncOptions(m);
  BindFields<HeldPose>(m, "HeldPose");
  BindFields<CalibrationOptions>(m, "CalibrationOptions")
      .def("check", &Check<CalibrationOptions>,
           "Raises ValueError naming every field out of range (one message per condition).");
}

}  // namespace mocap::bindings
