// Python bindings of the host library: module mocap._core.
// Arrays are numpy float64. Quaternions cross this boundary in (w, x, y, z) order.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <stdexcept>

#include "mocap/camera.h"
#include "mocap/initialisation.h"
#include "mocap/kinematics.h"
#include "mocap/prior.h"
#include "mocap/residuals/point_residual.h"
#include "mocap/sites.h"
#include "mocap/skeleton.h"
#include "mocap/so3.h"
#include "mocap/solver.h"
#include "mocap/window_calibration.h"
#include "pipeline.h"

namespace py = pybind11;
using namespace mocap;

namespace {

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

// Runs load(&value, &error); throws ValueError with the error when it fails.
template <typename T, typename Load>
T Checked(Load load) {
  T value;
  std::string error;
  if (!load(&value, &error)) throw std::invalid_argument(error);
  return value;
}

Skeleton SkeletonFromBones(const std::vector<std::string>& names, const std::vector<int>& parents,
                           const Eigen::MatrixX3d& offsets) {
  if (names.size() != parents.size() || static_cast<long>(names.size()) != offsets.rows()) {
    throw std::invalid_argument("names, parents and offsets must have the same length");
  }
  std::vector<Skeleton::Bone> bones;
  for (size_t b = 0; b < names.size(); ++b)
    bones.push_back({names[b], parents[b], offsets.row(b).transpose()});
  return Checked<Skeleton>(
      [&](Skeleton* s, std::string* e) { return Skeleton::Create(std::move(bones), s, e); });
}

py::tuple Fk(const Skeleton& s, const Eigen::VectorXd& theta) {
  if (theta.size() != s.pose_dim()) throw std::invalid_argument("theta has the wrong size");
  BodyPose pose;
  ForwardKinematics(s, theta.data(), &pose);
  Array rot({s.num_bones(), 3, 3}), pos({s.num_bones(), 3});
  auto r = rot.mutable_unchecked<3>();
  auto p = pos.mutable_unchecked<2>();
  for (int b = 0; b < s.num_bones(); ++b) {
    for (int i = 0; i < 3; ++i) {
      p(b, i) = pose.position[b](i);
      for (int j = 0; j < 3; ++j) r(b, i, j) = pose.rotation[b](i, j);
    }
  }
  return py::make_tuple(rot, pos);
}

// Pixels (N, 2) and a validity mask for world points (N, 3).
py::tuple Project(const Camera& c, const Eigen::MatrixX3d& points) {
  Array px({static_cast<long>(points.rows()), 2L});
  py::array_t<bool> ok(points.rows());
  auto p = px.mutable_unchecked<2>();
  auto o = ok.mutable_unchecked<1>();
  for (long i = 0; i < points.rows(); ++i) {
    Eigen::Vector2d q(NAN, NAN);
    o(i) = c.Project(points.row(i).transpose(), &q);
    p(i, 0) = o(i) ? q.x() : NAN;
    p(i, 1) = o(i) ? q.y() : NAN;
  }
  return py::make_tuple(px, ok);
}

// keypoints: (C, K, 3) [x, y, confidence] for the cameras listed; quaternions (M, 4) w, x, y, z;
// accelerations (M, 3). NaN marks a missing orientation or acceleration.
FrameObservations MakeFrame(double timestamp, const std::vector<int>& cameras, Array keypoints,
                            const std::vector<int>& imus, Array quaternions, Array accelerations) {
  FrameObservations f;
  f.timestamp = timestamp;
  if (!cameras.empty()) {
    if (keypoints.ndim() != 3 || keypoints.shape(0) != static_cast<long>(cameras.size()) ||
        keypoints.shape(2) != 3) {
      throw std::invalid_argument("keypoints must be (cameras, keypoints, 3)");
    }
    auto k = keypoints.unchecked<3>();
    for (size_t c = 0; c < cameras.size(); ++c) {
      CameraObservation obs;
      obs.camera = cameras[c];
      for (long i = 0; i < k.shape(1); ++i)
        obs.keypoints.push_back({k(c, i, 0), k(c, i, 1), k(c, i, 2)});
      f.cameras.push_back(std::move(obs));
    }
  }
  if (!imus.empty()) {
    const long m = static_cast<long>(imus.size());
    if (quaternions.ndim() != 2 || quaternions.shape(0) != m || quaternions.shape(1) != 4 ||
        accelerations.ndim() != 2 || accelerations.shape(0) != m || accelerations.shape(1) != 3) {
      throw std::invalid_argument("quaternions must be (imus, 4) and accelerations (imus, 3)");
    }
    auto q = quaternions.unchecked<2>();
    auto a = accelerations.unchecked<2>();
    for (long i = 0; i < m; ++i) {
      ImuObservation obs;
      obs.imu = imus[i];
      obs.orientation = Eigen::Quaterniond(q(i, 0), q(i, 1), q(i, 2), q(i, 3));
      obs.acceleration = Eigen::Vector3d(a(i, 0), a(i, 1), a(i, 2));
      obs.has_orientation = !std::isnan(q(i, 0));
      obs.has_acceleration = !std::isnan(a(i, 0));
      f.imus.push_back(obs);
    }
  }
  return f;
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "Host solver of the mocap system (C++ / Ceres).";

  m.def("so3_exp", &Exp, "Rotation matrix of a rotation vector.");
  m.def(
      "fit_to_points",
      [](const Skeleton& skeleton, const std::vector<int>& bones, const Eigen::MatrixX3d& offsets,
         const Eigen::MatrixX3d& targets, const Eigen::VectorXd& weights, Eigen::VectorXd theta,
         int max_iterations) {
        const size_t n = bones.size();
        if (offsets.rows() != static_cast<long>(n) || targets.rows() != static_cast<long>(n) ||
            weights.size() != static_cast<long>(n)) {
          throw std::invalid_argument(
              "bones, offsets, targets and weights must have one row per site");
        }
        std::vector<Site> sites(n);
        std::vector<Eigen::Vector3d> points(n);
        for (size_t i = 0; i < n; ++i) {
          sites[i] = {bones[i], offsets.row(i).transpose()};
          points[i] = targets.row(i).transpose();
        }
        const bool ok = FitToPoints(skeleton, sites, points,
                                    std::vector<double>(weights.data(), weights.data() + n),
                                    max_iterations, &theta);
        return py::make_tuple(ok, theta);
      },
      py::arg("skeleton"), py::arg("bones"), py::arg("offsets"), py::arg("targets"),
      py::arg("weights"), py::arg("theta"), py::arg("max_iterations") = 20,
      "Fit theta to 3D target points of sites (bone, offset); returns (ok, theta).");
  m.def("so3_log", &Log, "Rotation vector of a rotation matrix.");

  py::class_<Skeleton>(m, "Skeleton")
      .def_static("load",
                  [](const std::string& path) {
                    return Checked<Skeleton>([&](Skeleton* out, std::string* e) {
                      return LoadSkeletonJson(path, out, e);
                    });
                  })
      .def_static("from_json",
                  [](const std::string& text) {
                    return Checked<Skeleton>([&](Skeleton* out, std::string* e) {
                      return ParseSkeletonJson(text, out, e);
                    });
                  })
      .def_static("from_bones", &SkeletonFromBones, py::arg("names"), py::arg("parents"),
                  py::arg("offsets"))
      .def("to_json", &SkeletonToJson)
      .def_property_readonly("num_bones", &Skeleton::num_bones)
      .def_property_readonly("pose_dim", &Skeleton::pose_dim)
      .def_property_readonly("bone_names",
                             [](const Skeleton& s) {
                               std::vector<std::string> n;
                               for (const auto& b : s.bones()) n.push_back(b.name);
                               return n;
                             })
      .def_property_readonly("parents",
                             [](const Skeleton& s) {
                               std::vector<int> p;
                               for (const auto& b : s.bones()) p.push_back(b.parent);
                               return p;
                             })
      .def_property_readonly("offsets",
                             [](const Skeleton& s) {
                               Eigen::MatrixX3d o(s.num_bones(), 3);
                               for (int b = 0; b < s.num_bones(); ++b)
                                 o.row(b) = s.bone(b).offset.transpose();
                               return o;
                             })
      .def("bone_index", &Skeleton::BoneIndex)
      .def("rest_height", &Skeleton::RestHeight)
      .def("forward_kinematics", &Fk, py::arg("theta"),
           "(rotations (n, 3, 3) bone->world, positions (n, 3) of bone origins, metres)");

  py::class_<KeypointLayout>(m, "KeypointLayout")
      .def_static("load",
                  [](const std::string& path, const Skeleton& s) {
                    return Checked<KeypointLayout>([&](KeypointLayout* out, std::string* e) {
                      return LoadKeypointLayoutJson(path, s, out, e);
                    });
                  })
      .def("scaled_to", &KeypointLayout::ScaledTo)
      .def_readonly("name", &KeypointLayout::name)
      .def_readonly("names", &KeypointLayout::names)
      .def_property_readonly("bones",
                             [](const KeypointLayout& l) {
                               std::vector<int> b;
                               for (const auto& s : l.sites) b.push_back(s.bone);
                               return b;
                             })
      .def_property_readonly("offsets",
                             [](const KeypointLayout& l) {
                               Eigen::MatrixX3d o(l.size(), 3);
                               for (int k = 0; k < l.size(); ++k)
                                 o.row(k) = l.sites[k].offset.transpose();
                               return o;
                             })
      .def(
          "with_offsets",
          [](KeypointLayout l, const Eigen::MatrixX3d& offsets) {
            if (offsets.rows() != l.size()) throw std::invalid_argument("one offset per keypoint");
            for (int k = 0; k < l.size(); ++k) l.sites[k].offset = offsets.row(k).transpose();
            return l;
          },
          "A copy whose sites have these (K, 3) offsets (m, bone frames).")
      .def("__len__", &KeypointLayout::size);

  py::class_<ImuSite>(m, "ImuSite")
      .def(py::init<>())
      .def_readwrite("name", &ImuSite::name)
      .def_readwrite("bone", &ImuSite::bone)
      .def_readwrite("mount", &ImuSite::mount, "sensor -> bone rotation")
      .def_readwrite("offset", &ImuSite::offset, "bone frame, metres")
      .def_readwrite("reference", &ImuSite::reference, "IMU reference frame -> world rotation");
  m.def("load_imu_sites", [](const std::string& path, const Skeleton& s) {
    return Checked<std::vector<ImuSite>>([&](std::vector<ImuSite>* out, std::string* e) {
      return LoadImuSitesJson(path, s, out, e);
    });
  });
  m.def("imu_sites_to_json", &ImuSitesToJson, py::arg("skeleton"), py::arg("imus"),
        "The IMU set file (mocap.imus/1) of IMU sites.");
  m.def("layout_to_json", &KeypointLayoutToJson, py::arg("skeleton"), py::arg("layout"),
        "The layout file (mocap.layout/1), its offsets as they are for the skeleton.");

  py::class_<Camera>(m, "Camera")
      .def(py::init<>())
      .def_readwrite("name", &Camera::name)
      .def_readwrite("width", &Camera::width)
      .def_readwrite("height", &Camera::height)
      .def_readwrite("fx", &Camera::fx)
      .def_readwrite("fy", &Camera::fy)
      .def_readwrite("cx", &Camera::cx)
      .def_readwrite("cy", &Camera::cy)
      .def_readwrite("distortion", &Camera::distortion, "k1, k2, p1, p2, k3")
      .def_readwrite("rotation", &Camera::rotation, "world -> camera")
      .def_readwrite("translation", &Camera::translation, "world -> camera, metres")
      .def("center", &Camera::Center)
      .def(
          "undistort",
          [](const Camera& c, const Eigen::MatrixX2d& pixels) {
            Eigen::MatrixX2d out(pixels.rows(), 2);
            for (long i = 0; i < pixels.rows(); ++i)
              out.row(i) = c.Undistort(pixels.row(i).transpose()).transpose();
            return out;
          },
          "normalised image coordinates (N, 2) of pixels (N, 2)")
      .def("project", &Project, "(pixels (N, 2), valid (N,)) for world points (N, 3)");

  py::class_<Rig>(m, "Rig")
      .def(py::init<>())
      .def(py::init([](std::vector<Camera> c) {
        Rig r;
        r.cameras = std::move(c);
        return r;
      }))
      .def_static("load",
                  [](const std::string& path) {
                    return Checked<Rig>(
                        [&](Rig* out, std::string* e) { return LoadRigJson(path, out, e); });
                  })
      .def_static("from_json",
                  [](const std::string& text) {
                    return Checked<Rig>(
                        [&](Rig* out, std::string* e) { return ParseRigJson(text, out, e); });
                  })
      .def("to_json", &RigToJson)
      .def_readwrite("cameras", &Rig::cameras);

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

  py::enum_<LossType>(m, "LossType")
      .value("TRIVIAL", LossType::kTrivial)
      .value("CAUCHY", LossType::kCauchy)
      .value("HUBER", LossType::kHuber);
  py::class_<TermOptions>(m, "TermOptions")
      .def(py::init<>())
      .def_readwrite("enabled", &TermOptions::enabled)
      .def_readwrite("weight", &TermOptions::weight)
      .def_readwrite("loss", &TermOptions::loss)
      .def_readwrite("loss_scale", &TermOptions::loss_scale);
  py::class_<SolverOptions>(m, "SolverOptions")
      .def(py::init<>())
      .def_readwrite("orientation", &SolverOptions::orientation)
      .def_readwrite("position", &SolverOptions::position)
      .def_readwrite("acceleration", &SolverOptions::acceleration)
      .def_readwrite("pca_projection", &SolverOptions::pca_projection)
      .def_readwrite("pca_deviation", &SolverOptions::pca_deviation)
      .def_readwrite("accel_at_rest", &SolverOptions::accel_at_rest)
      .def_readwrite("min_confidence", &SolverOptions::min_confidence)
      .def_readwrite("predict_motion", &SolverOptions::predict_motion)
      .def_readwrite("max_quaternion_error", &SolverOptions::max_quaternion_error)
      .def_readwrite("max_history_gap", &SolverOptions::max_history_gap)
      .def_readwrite("velocity_gain", &SolverOptions::velocity_gain)
      .def_readwrite("max_keypoint_cost", &SolverOptions::max_keypoint_cost)
      .def_readwrite("heading_time_constant", &SolverOptions::heading_time_constant)
      .def_readwrite("max_heading_step", &SolverOptions::max_heading_step)
      .def_readwrite("heading_baseline_s", &SolverOptions::heading_baseline_s)
      .def_readwrite("max_iterations", &SolverOptions::max_iterations)
      .def_readwrite("max_initial_iterations", &SolverOptions::max_initial_iterations)
      .def_readwrite("function_tolerance", &SolverOptions::function_tolerance)
      .def_readwrite("parameter_tolerance", &SolverOptions::parameter_tolerance)
      .def_readwrite("gradient_tolerance", &SolverOptions::gradient_tolerance);

  py::class_<SolveResult>(m, "SolveResult")
      .def_property_readonly("status",
                             [](const SolveResult& r) { return std::string(ToString(r.status)); })
      .def_readonly("theta", &SolveResult::theta)
      .def_readonly("timestamp", &SolveResult::timestamp)
      .def_readonly("iterations", &SolveResult::iterations)
      .def_readonly("solve_time_ms", &SolveResult::solve_time_ms)
      .def_readonly("message", &SolveResult::message)
      .def_property_readonly(
          "timings_ms",
          [](const SolveResult& r) {
            const SolveTimings& t = r.timings;
            return py::dict(py::arg("ceres") = t.ceres, py::arg("linear_solver") = t.linear_solver,
                            py::arg("jacobian_evaluation") = t.jacobian_evaluation,
                            py::arg("residual_evaluation") = t.residual_evaluation);
          })
      .def_property_readonly(
          "position_unconstrained",
          [](const SolveResult& r) { return bool(r.flags & kPositionUnconstrained); })
      .def_property_readonly("iteration_limit",
                             [](const SolveResult& r) { return bool(r.flags & kIterationLimit); })
      .def_property_readonly(
          "lost_and_reacquired",
          [](const SolveResult& r) { return bool(r.flags & kLostAndReacquired); })
      .def_property_readonly("costs",
                             [](const SolveResult& r) {
                               const TermCosts& c = r.costs;
                               return py::dict(py::arg("orientation") = c.orientation,
                                               py::arg("position") = c.position,
                                               py::arg("acceleration") = c.acceleration,
                                               py::arg("pca_projection") = c.pca_projection,
                                               py::arg("pca_deviation") = c.pca_deviation);
                             })
      .def_property_readonly("counts", [](const SolveResult& r) {
        const InputCounts& c = r.counts;
        return py::dict(py::arg("keypoints_used") = c.keypoints_used,
                        py::arg("keypoints_not_detected") = c.keypoints_not_detected,
                        py::arg("keypoints_invalid") = c.keypoints_invalid,
                        py::arg("keypoints_behind_camera") = c.keypoints_behind_camera,
                        py::arg("orientations_used") = c.orientations_used,
                        py::arg("orientations_invalid") = c.orientations_invalid,
                        py::arg("accelerations_used") = c.accelerations_used,
                        py::arg("accelerations_invalid") = c.accelerations_invalid,
                        py::arg("unknown_sources") = c.unknown_sources);
      });

  py::class_<Solver>(m, "Solver")
      .def(py::init([](Skeleton s, Rig r, KeypointLayout l, std::vector<ImuSite> i,
                       std::optional<PosePrior> p, SolverOptions o) {
             std::string e;
             auto solver = Solver::Create(std::move(s), std::move(r), std::move(l), std::move(i),
                                          std::move(p), o, &e);
             if (!solver) throw std::invalid_argument(e);
             return solver;
           }),
           py::arg("skeleton"), py::arg("rig"), py::arg("layout"), py::arg("imus"),
           py::arg("prior") = py::none(), py::arg("options") = SolverOptions())
      .def(
          "solve",
          [](Solver& s, double t, const std::vector<int>& cameras, Array keypoints,
             const std::vector<int>& imus, Array quaternions, Array accelerations) {
            const FrameObservations f =
                MakeFrame(t, cameras, keypoints, imus, quaternions, accelerations);
            py::gil_scoped_release release;
            return s.Solve(f);
          },
          py::arg("timestamp"), py::arg("cameras"), py::arg("keypoints"), py::arg("imus"),
          py::arg("quaternions_wxyz"), py::arg("accelerations"),
          "Solve one frame. keypoints (C, K, 3) pixels+confidence for the listed cameras; "
          "quaternions (M, 4) sensor->IMU reference, w first; accelerations (M, 3) m/s^2 in the "
          "sensor frame with gravity. NaN marks a missing reading.")
      .def("reset", &Solver::Reset)
      .def_property(
          "options", [](const Solver& s) { return SolverOptions(s.options()); },  // a copy
          [](Solver& s, const SolverOptions& o) {
            std::string e;
            if (!s.SetOptions(o, &e)) throw std::invalid_argument(e);
          },
          "Replace the options from the next frame on (ValueError when out of range).")
      .def("set_warm_start", &Solver::SetWarmStart)
      .def_property_readonly("pose", &Solver::pose)
      .def_property_readonly("headings", &Solver::headings,
                             "heading corrections psi_i (rad about world z), one per IMU site")
      .def_property_readonly("initialised", &Solver::initialised);

  py::class_<HeldPose>(m, "HeldPose")
      .def(py::init<>())
      .def_readwrite("frame", &HeldPose::frame)
      .def_readwrite("theta", &HeldPose::theta)
      .def_readwrite("sigma", &HeldPose::sigma);
  py::class_<CalibrationOptions>(m, "CalibrationOptions")
      .def(py::init<>())
      .def_readwrite("terms", &CalibrationOptions::terms)
      .def_readwrite("scale_group", &CalibrationOptions::scale_group)
      .def_readwrite("shift_group", &CalibrationOptions::shift_group)
      .def_readwrite("scale_sigma", &CalibrationOptions::scale_sigma)
      .def_readwrite("shift_sigma", &CalibrationOptions::shift_sigma)
      .def_readwrite("shift_sigmas", &CalibrationOptions::shift_sigmas)
      .def_readwrite("joint_sigmas", &CalibrationOptions::joint_sigmas)
      .def_readwrite("held_poses", &CalibrationOptions::held_poses)
      .def_readwrite("heading_priors", &CalibrationOptions::heading_priors)
      .def_readwrite("estimate_shifts", &CalibrationOptions::estimate_shifts)
      .def_readwrite("site_sigma", &CalibrationOptions::site_sigma)
      .def_readwrite("site_observable_std", &CalibrationOptions::site_observable_std)
      .def_readwrite("estimate_scales", &CalibrationOptions::estimate_scales)
      .def_readwrite("estimate_sites", &CalibrationOptions::estimate_sites)
      .def_readwrite("estimate_mounts", &CalibrationOptions::estimate_mounts)
      .def_readwrite("estimate_headings", &CalibrationOptions::estimate_headings)
      .def_readwrite("max_iterations", &CalibrationOptions::max_iterations)
      .def_readwrite("num_threads", &CalibrationOptions::num_threads);
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
  m.def(
      "calibrate_window",
      [](const Skeleton& s, const Rig& r, const KeypointLayout& l, const std::vector<ImuSite>& i,
         std::optional<PosePrior> p, const py::list& frames,
         const std::vector<Eigen::VectorXd>& thetas, const CalibrationOptions& o) {
        std::vector<FrameObservations> obs;
        for (const py::handle& f : frames) {
          const auto t = f.cast<py::tuple>();
          if (t.size() != 6)
            throw std::invalid_argument(
                "a frame is (time, cameras, keypoints, imus, quaternions, accelerations)");
          obs.push_back(MakeFrame(t[0].cast<double>(), t[1].cast<std::vector<int>>(),
                                  t[2].cast<Array>(), t[3].cast<std::vector<int>>(),
                                  t[4].cast<Array>(), t[5].cast<Array>()));
        }
        CalibrationResult result;
        std::string e;
        bool ok;
        {
          py::gil_scoped_release release;
          ok = CalibrateWindow(s, r, l, i, p, obs, thetas, o, &result, &e);
        }
        if (!ok) throw std::invalid_argument(e);
        return result;
      },
      py::arg("skeleton"), py::arg("rig"), py::arg("layout"), py::arg("imus"), py::arg("prior"),
      py::arg("frames"), py::arg("thetas"), py::arg("options") = CalibrationOptions(),
      "Bone lengths, keypoint sites, IMU mountings and headings over a window of frames "
      "(window_calibration.h). frames: [(time, cameras, keypoints, imus, quaternions, "
      "accelerations)] as Solver.solve takes them; thetas: the frames' starting poses.");

  // The live host's pipeline without the transport (host/daemon/pipeline.h): an offline
  // solve of a recording feeds it the recorded messages with their arrival times.
  py::class_<HostPipeline>(m, "HostPipeline")
      .def_static(
          "load",
          [](const std::string& session_path) {
            Session session;
            std::string e;
            if (!LoadSession(session_path, &session, &e)) throw std::invalid_argument(e);
            auto p = HostPipeline::Create(std::move(session), &e);
            if (!p) throw std::invalid_argument(e);
            return p;
          },
          py::arg("session_path"), "A pipeline from a session file (ValueError when it is wrong).")
      .def(
          "feed",
          [](HostPipeline& p, py::bytes type, py::bytes payload, int64_t now_ns) {
            std::string why;
            const bool ok = p.Feed(std::string(type), std::string(payload), now_ns, &why);
            return py::make_tuple(ok, why);
          },
          py::arg("type"), py::arg("payload"), py::arg("now_ns"),
          "Feed one message; (accepted, why it was dropped).")
      .def(
          "solve",
          [](HostPipeline& p, int64_t now_ns) {
            std::vector<SolvedFrame> frames;
            {
              py::gil_scoped_release release;
              frames = p.Solve(now_ns);
            }
            py::list out;
            for (const SolvedFrame& f : frames)
              out.append(py::make_tuple(py::bytes(f.pose.SerializeAsString()), f.last_input_ns));
            return out;
          },
          py::arg("now_ns"), "Frames ready at now_ns: [(PoseFrame bytes, last input arrival ns)].")
      .def("health", [](HostPipeline& p,
                        int64_t now_ns) { return py::bytes(p.Health(now_ns).SerializeAsString()); })
      .def_property_readonly("dropped", &HostPipeline::dropped)
      .def_property_readonly(
          "skeleton", [](const HostPipeline& p) { return p.session().skeleton; },
          "the skeleton in use: the session's, or the latest calibration's")
      .def_property_readonly("calibrations_applied", &HostPipeline::calibrations_applied)
      .def_property_readonly("frames_solved", &HostPipeline::frames_solved);
}
