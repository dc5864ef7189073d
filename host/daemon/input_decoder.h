// From checked wire messages (wire.h) to the synchroniser's inputs (stream_sync.h): camera
// ids to the rig's cameras, sensor ids to the IMU set, each person's keypoints checked
// against the session's layout, the IMU status bits to what a reading carries.
#ifndef MOCAP_DAEMON_INPUT_DECODER_H_
#define MOCAP_DAEMON_INPUT_DECODER_H_

#include <string>
#include <unordered_map>
#include <vector>

#include "mocap/camera.h"
#include "mocap/sites.h"
#include "mocap/stream_sync.h"
#include "mocap/v1/imu_batch.pb.h"
#include "mocap/v1/keypoint_frame.pb.h"

namespace mocap {

// Why a message is dropped: the counter it is counted under, and a detail for the log.
struct Rejection {
  std::string reason;  // e.g. "unknown_source", "invalid"
  std::string detail;
};

class InputDecoder {
 public:
  InputDecoder(const Rig& rig, const std::vector<ImuSite>& imus, const KeypointLayout& layout);

  // The rig's index of the frame's camera; false with *why when the camera is not in the rig
  // ("unknown_source") or a person has another layout or keypoint count ("invalid"; *camera
  // is set then, for the camera's statistics).
  bool CameraOf(const v1::KeypointFrame& frame, int* camera, Rejection* why) const;
  // The synchroniser's input of a frame of `camera`: the keypoints of person `subject`, none
  // when subject < 0 (the frame was not detected or has nobody).
  CameraInput ToCameraInput(const v1::KeypointFrame& frame, int camera, int subject) const;
  // The frame with every person in CameraInput::persons (a session of several people).
  CameraInput ToCameraInputEveryone(const v1::KeypointFrame& frame, int camera) const;

  // The IMU set's index of a sensor, -1 when it is not in the set.
  int ImuOf(const std::string& sensor_id) const;
  // A sample as the synchroniser takes it (quaternion w, x, y, z on the wire; status bits
  // mark an invalid orientation or acceleration).
  static ImuInput ToImuInput(const v1::ImuSample& sample, int imu);

  // The session's keypoint layout: its name and keypoints per person.
  const std::string& layout_name() const { return layout_name_; }
  int layout_size() const { return layout_size_; }

 private:
  std::unordered_map<std::string, int> camera_index_, imu_index_;
  std::string layout_name_;
  int layout_size_;
};

}  // namespace mocap

#endif  // MOCAP_DAEMON_INPUT_DECODER_H_
