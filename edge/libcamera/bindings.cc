// mocap_edge.sources._libcamera: the capture (capture.h) for the camera box's `libcamera:`
// source. Next() waits without the GIL; a frame comes back as (image (H, W, 3) uint8 R, G, B,
// sequence, sensor timestamp ns or None, exposure us or None).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>

#include "capture.h"

namespace py = pybind11;
using mocap::edge::Capture;
using mocap::edge::CaptureConfig;
using mocap::edge::CapturedFrame;

namespace {

py::object Next(Capture& capture, double timeout_s) {
  std::optional<CapturedFrame> frame;
  {
    py::gil_scoped_release release;
    frame = capture.Next(timeout_s);
  }
  if (!frame) return py::none();
  py::array_t<uint8_t> image({static_cast<py::ssize_t>(frame->height),
                              static_cast<py::ssize_t>(frame->width), py::ssize_t{3}});
  std::memcpy(image.mutable_data(), frame->rgb.data(), frame->rgb.size());
  return py::make_tuple(image, frame->sequence, frame->sensor_timestamp_ns, frame->exposure_us);
}

std::unique_ptr<Capture> Open(const std::string& camera, unsigned width, unsigned height,
                              double fps, unsigned buffer_count) {
  CaptureConfig config{camera, width, height, fps, buffer_count};
  py::gil_scoped_release release;  // libcamera's start enumerates devices
  return std::make_unique<Capture>(config);
}

}  // namespace

PYBIND11_MODULE(_libcamera, m) {
  m.doc() = "A camera through libcamera's C++ API (edge/libcamera/capture.h)";
  py::register_exception<mocap::edge::CaptureError>(m, "CaptureError", PyExc_RuntimeError);
  m.def("list_cameras", &mocap::edge::ListCameras, "the ids of the cameras found, in index order");
  m.def("version", &mocap::edge::LibcameraVersion, "libcamera's version this was built against");
  py::class_<Capture>(m, "Capture")
      .def(py::init(&Open), py::arg("camera"), py::arg("width") = 1280, py::arg("height") = 720,
           py::arg("fps") = 60.0, py::arg("buffer_count") = 4)
      .def("next", &Next, py::arg("timeout_s"))
      .def("close", &Capture::Close)
      .def_property_readonly("id", &Capture::id)
      .def_property_readonly("size",
                             [](const Capture& c) { return py::make_tuple(c.width(), c.height()); })
      .def_property_readonly("pixel_format", &Capture::pixel_format)
      .def_property_readonly("dropped", &Capture::dropped)
      .def_property_readonly("failed", &Capture::failed);
}
