#include "input_decoder.h"

#include <algorithm>

namespace mocap {

InputDecoder::InputDecoder(const Rig& rig, const std::vector<ImuSite>& imus,
                           const KeypointLayout& layout)
    : layout_name_(layout.name), layout_size_(layout.size()) {
  for (size_t c = 0; c < rig.cameras.size(); ++c) camera_index_[rig.cameras[c].name] = c;
  for (size_t i = 0; i < imus.size(); ++i) imu_index_[imus[i].name] = i;
}

bool InputDecoder::CameraOf(const v1::KeypointFrame& frame, int* camera, Rejection* why) const {
  const auto it = camera_index_.find(frame.camera_id());
  if (it == camera_index_.end()) {
    *why = {"unknown_source", "camera '" + frame.camera_id() + "' is not in the rig"};
    return false;
  }
  *camera = it->second;
  const bool wrong_layout =
      frame.detected() && !frame.persons().empty() && frame.keypoint_layout() != layout_name_;
  const bool wrong_size =
      frame.detected() &&
      std::any_of(frame.persons().begin(), frame.persons().end(),
                  [&](const v1::KeypointPerson& p) { return p.x_size() != layout_size_; });
  if (wrong_layout || wrong_size) {
    *why = {"invalid", frame.camera_id() + ": layout '" + frame.keypoint_layout() +
                           "' or keypoint count is not the session's " + layout_name_ + " (" +
                           std::to_string(layout_size_) + ")"};
    return false;
  }
  return true;
}

CameraInput InputDecoder::ToCameraInput(const v1::KeypointFrame& frame, int camera,
                                        int subject) const {
  CameraInput in;
  in.camera = camera;
  in.time_ns = frame.capture_time_ns();
  in.detected = frame.detected();
  if (subject < 0) return in;
  const v1::KeypointPerson& p = frame.persons(subject);
  in.keypoints.resize(layout_size_);
  for (int k = 0; k < layout_size_; ++k)
    in.keypoints[k] = Keypoint2D{p.x(k), p.y(k), p.confidence(k)};
  return in;
}

CameraInput InputDecoder::ToCameraInputEveryone(const v1::KeypointFrame& frame, int camera) const {
  CameraInput in = ToCameraInput(frame, camera, -1);
  for (const v1::KeypointPerson& p : frame.persons()) {
    std::vector<Keypoint2D>& person = in.persons.emplace_back(layout_size_);
    for (int k = 0; k < layout_size_; ++k) person[k] = Keypoint2D{p.x(k), p.y(k), p.confidence(k)};
  }
  return in;
}

int InputDecoder::ImuOf(const std::string& sensor_id) const {
  const auto it = imu_index_.find(sensor_id);
  return it == imu_index_.end() ? -1 : it->second;
}

ImuInput InputDecoder::ToImuInput(const v1::ImuSample& s, int imu) {
  ImuInput in;
  in.imu = imu;
  in.time_ns = s.sample_time_ns();
  in.orientation = Eigen::Quaterniond(s.qw(), s.qx(), s.qy(), s.qz());
  in.acceleration = {s.ax(), s.ay(), s.az()};
  in.has_orientation = !(s.status() & v1::ImuSample::STATUS_ORIENTATION_INVALID);
  in.has_acceleration = !(s.status() & v1::ImuSample::STATUS_ACCELERATION_INVALID);
  return in;
}

}  // namespace mocap
