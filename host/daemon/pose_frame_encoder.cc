#include "pose_frame_encoder.h"

#include <algorithm>

#include "mocap/kinematics.h"

namespace mocap {
namespace {

void AddJoints(const Skeleton& skeleton, const Eigen::VectorXd& theta, v1::PoseFrame* p) {
  BodyPose pose;
  ForwardKinematics(skeleton, theta.data(), &pose);
  for (int b = 0; b < skeleton.num_bones(); ++b) {
    v1::JointTransform* j = p->add_joints();
    const Eigen::Quaterniond q(pose.rotation[b]);
    j->set_name(skeleton.bone(b).name);
    j->set_px(pose.position[b].x()), j->set_py(pose.position[b].y());
    j->set_pz(pose.position[b].z());
    j->set_qw(q.w()), j->set_qx(q.x()), j->set_qy(q.y()), j->set_qz(q.z());
  }
}

void SetCosts(const TermCosts& c, v1::TermCosts* costs) {
  costs->set_orientation(c.orientation);
  costs->set_position(c.position);
  costs->set_acceleration(c.acceleration);
  costs->set_pca_projection(c.pca_projection);
  costs->set_pca_deviation(c.pca_deviation);
  costs->set_motion(c.motion);
  costs->set_ground(c.ground);
}

}  // namespace

v1::PoseFrame::Status ToProto(SolveStatus s) {
  switch (s) {
    case SolveStatus::kOk:
      return v1::PoseFrame::STATUS_OK;
    case SolveStatus::kInitialised:
      return v1::PoseFrame::STATUS_INITIALISED;
    case SolveStatus::kNoObservations:
      return v1::PoseFrame::STATUS_NO_OBSERVATIONS;
    case SolveStatus::kRejectedFrame:
      return v1::PoseFrame::STATUS_REJECTED_FRAME;
    case SolveStatus::kFailed:
      return v1::PoseFrame::STATUS_FAILED;
  }
  return v1::PoseFrame::STATUS_FAILED;
}

v1::PoseFrame EncodePoseFrame(const FrameObservations& frame, const SolveResult& r,
                              int64_t capture_time_ns, uint64_t frame_index,
                              const Skeleton& skeleton, const Rig& rig,
                              const std::vector<ImuSite>& imus) {
  v1::PoseFrame p;
  p.set_capture_time_ns(capture_time_ns);
  p.set_frame_index(frame_index);
  p.set_status(ToProto(r.status));
  for (int i = 0; i < r.theta.size(); ++i) p.add_theta(r.theta[i]);
  AddJoints(skeleton, r.theta, &p);
  SetCosts(r.costs, p.mutable_costs());
  p.set_iterations(r.iterations);
  p.set_solve_time_ms(r.solve_time_ms);
  p.set_quality_flags(r.flags);
  for (const CameraObservation& c : frame.cameras) p.add_cameras(rig.cameras[c.camera].name);
  for (const ImuObservation& i : frame.imus) {
    const bool distrusted = std::count(r.imus_distrusted.begin(), r.imus_distrusted.end(), i.imu);
    if (!distrusted) p.add_imus(imus[i.imu].name);
  }
  for (int i : r.imus_distrusted) p.add_imus_distrusted(imus[i].name);
  return p;
}

}  // namespace mocap
