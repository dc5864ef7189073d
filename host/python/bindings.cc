// Python bindings of the host library: module mocap._core, one file per area
// (bindings_<area>.cc). Arrays are numpy float64. Quaternions cross this boundary in
// (w, x, y, z) order.
#include "bindings.h"

#include <cmath>

namespace mocap::bindings {
namespace {

void AddCameras(const std::vector<int>& cameras, const Array& keypoints, FrameObservations* f) {
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
    f->cameras.push_back(std::move(obs));
  }
}

void AddImus(const std::vector<int>& imus, const Array& quaternions, const Array& accelerations,
             FrameObservations* f) {
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
    f->imus.push_back(obs);
  }
}

}  // namespace

FrameObservations MakeFrame(double timestamp, const std::vector<int>& cameras, Array keypoints,
                            const std::vector<int>& imus, Array quaternions, Array accelerations) {
  FrameObservations f;
  f.timestamp = timestamp;
  if (!cameras.empty()) AddCameras(cameras, keypoints, &f);
  if (!imus.empty()) AddImus(imus, quaternions, accelerations, &f);
  return f;
}

}  // namespace mocap::bindings

PYBIND11_MODULE(_core, m) {
  using namespace mocap::bindings;
  m.doc() = "Host solver of the mocap system (C++ / Ceres).";
  BindGeometry(m);
  BindSites(m);
  BindCamera(m);
  BindOptions(m);
  BindSolver(m);
  BindCalibration(m);
  BindPipeline(m);
  BindInput(m);
  BindTracker(m);
}
