// The PoseFrame a solved frame is published as (proto/mocap/v1/pose_frame.proto): the pose
// vector, every bone's world transform, the solve's status, costs and timing, and the
// cameras and IMUs it was solved with.
#ifndef MOCAP_DAEMON_POSE_FRAME_ENCODER_H_
#define MOCAP_DAEMON_POSE_FRAME_ENCODER_H_

#include <cstdint>
#include <vector>

#include "mocap/solver.h"
#include "mocap/v1/pose_frame.pb.h"

namespace mocap {

v1::PoseFrame::Status ToProto(SolveStatus status);

// frame: the observations solved with (their camera and IMU indices name the rig's cameras
// and the IMU set's sensors); joints: forward kinematics of result.theta on `skeleton`,
// quaternions w, x, y, z. latency_ms is left to the publisher.
v1::PoseFrame EncodePoseFrame(const FrameObservations& frame, const SolveResult& result,
                              int64_t capture_time_ns, uint64_t frame_index,
                              const Skeleton& skeleton, const Rig& rig,
                              const std::vector<ImuSite>& imus);

}  // namespace mocap

#endif  // MOCAP_DAEMON_POSE_FRAME_ENCODER_H_
