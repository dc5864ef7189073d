// What the host pipeline's tests feed it: a pipeline for a synthetic scene's session, and a
// camera box's KeypointFrame of the people it sees.
#ifndef MOCAP_DAEMON_PIPELINE_TEST_MESSAGES_H_
#define MOCAP_DAEMON_PIPELINE_TEST_MESSAGES_H_

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "pipeline.h"
#include "synthetic_scene.h"

namespace mocap::testing {

// The pipeline of a session made of the scene (its skeleton, rig, layout and IMU set).
inline std::unique_ptr<HostPipeline> ScenePipeline(const Scene& scene, int people = 1,
                                                   bool imus_calibrated = true) {
  Session s;
  s.skeleton = scene.skeleton, s.rig = scene.rig, s.layout = scene.layout, s.imus = scene.imus;
  s.people = people;
  s.imus_calibrated = imus_calibrated;
  std::string error;
  auto p = HostPipeline::Create(s, &error);
  EXPECT_TRUE(p) << error;
  return p;
}

// Camera c's frame k, captured at capture_ns, listing `persons` (each the layout's keypoints).
inline std::string CameraFrame(const Scene& scene, int c, int k, int64_t capture_ns,
                               const std::vector<std::vector<Keypoint2D>>& persons) {
  v1::KeypointFrame f;
  f.set_camera_id(scene.rig.cameras[c].name);
  f.set_frame_index(k);
  f.set_capture_time_ns(capture_ns);
  f.set_keypoint_layout(scene.layout.name);
  f.set_detected(true);
  for (const std::vector<Keypoint2D>& keypoints : persons) {
    v1::KeypointPerson* person = f.add_persons();
    for (const Keypoint2D& kp : keypoints)
      person->add_x(kp.x), person->add_y(kp.y), person->add_confidence(kp.confidence);
  }
  return f.SerializeAsString();
}

}  // namespace mocap::testing

#endif  // MOCAP_DAEMON_PIPELINE_TEST_MESSAGES_H_
