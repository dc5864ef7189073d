// Cameras (OpenCV pinhole with distortion) and the rig.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <cmath>

#include "bindings.h"
#include "mocap/camera.h"

namespace mocap::bindings {
namespace {

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

Eigen::MatrixX2d Undistort(const Camera& c, const Eigen::MatrixX2d& pixels) {
  Eigen::MatrixX2d out(pixels.rows(), 2);
  for (long i = 0; i < pixels.rows(); ++i)
    out.row(i) = c.Undistort(pixels.row(i).transpose()).transpose();
  return out;
}

void BindRig(py::module_& m) {
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
}

}  // namespace

void BindCamera(py::module_& m) {
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
      .def("undistort", &Undistort, "normalised image coordinates (N, 2) of pixels (N, 2)")
      .def("project", &Project, "(pixels (N, 2), valid (N,)) for world points (N, 3)");
  BindRig(m);
}

}  // namespace mocap::bindings
