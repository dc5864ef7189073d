// SO(3), the skeleton and its forward kinematics, and the fit of a pose to 3D points.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "mocap/kinematics.h"
#include "mocap/skeleton.h"
#include "mocap/so3.h"
#include "mocap/solver.h"

namespace mocap::bindings {
namespace {

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

py::tuple FitToSites(const Skeleton& skeleton, const std::vector<int>& bones,
                     const Eigen::MatrixX3d& offsets, const Eigen::MatrixX3d& targets,
                     const Eigen::VectorXd& weights, Eigen::VectorXd theta, int max_iterations) {
  const size_t n = bones.size();
  if (offsets.rows() != static_cast<long>(n) || targets.rows() != static_cast<long>(n) ||
      weights.size() != static_cast<long>(n)) {
    throw std::invalid_argument("bones, offsets, targets and weights must have one row per site");
  }
  std::vector<Site> sites(n);
  std::vector<Eigen::Vector3d> points(n);
  for (size_t i = 0; i < n; ++i) {
    sites[i] = {bones[i], offsets.row(i).transpose()};
    points[i] = targets.row(i).transpose();
  }
  const bool ok =
      FitToPoints(skeleton, sites, points, std::vector<double>(weights.data(), weights.data() + n),
                  max_iterations, &theta);
  return py::make_tuple(ok, theta);
}

void BindSkeletonFiles(py::class_<Skeleton>* c) {
  c->def_static("load",
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
      .def("to_json", &SkeletonToJson);
}

void BindSkeleton(py::module_& m) {
  py::class_<Skeleton> c(m, "Skeleton");
  BindSkeletonFiles(&c);
  c.def_property_readonly("num_bones", &Skeleton::num_bones)
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
}

}  // namespace

void BindGeometry(py::module_& m) {
  m.def("so3_exp", &Exp, "Rotation matrix of a rotation vector.");
  m.def("so3_log", &Log, "Rotation vector of a rotation matrix.");
  m.def("fit_to_points", &FitToSites, py::arg("skeleton"), py::arg("bones"), py::arg("offsets"),
        py::arg("targets"), py::arg("weights"), py::arg("theta"), py::arg("max_iterations") = 20,
        "Fit theta to 3D target points of sites (bone, offset); returns (ok, theta).");
  BindSkeleton(m);
}

}  // namespace mocap::bindings
