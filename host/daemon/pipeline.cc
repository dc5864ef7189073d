#include "pipeline.h"

#include "pose_frame_encoder.h"
#include "subject_selector.h"

namespace mocap {
namespace {

template <typename T>
std::vector<std::string> Names(const std::vector<T>& items) {
  std::vector<std::string> names;
  for (const T& item : items) names.push_back(item.name);
  return names;
}

}  // namespace

std::unique_ptr<HostPipeline> HostPipeline::Create(Session session, std::string* error) {
  auto solver = Solver::Create(session.skeleton, session.rig, session.layout, session.imus,
                               session.prior, session.solver, error);
  if (!solver) return nullptr;
  return std::unique_ptr<HostPipeline>(new HostPipeline(std::move(session), std::move(solver)));
}

HostPipeline::HostPipeline(Session session, std::unique_ptr<Solver> solver)
    : session_(std::move(session)),
      step_(std::move(solver), session_.imus_calibrated),
      decoder_(session_.rig, session_.imus, session_.layout),
      sync_(static_cast<int>(session_.rig.cameras.size()), static_cast<int>(session_.imus.size()),
            session_.sync),
      monitor_(Names(session_.rig.cameras), Names(session_.imus)) {}

bool HostPipeline::Feed(std::string_view type, std::string_view payload, int64_t now_ns,
                        std::string* why) {
  wire::Decoded d = wire::DecodeMessage(type, payload);
  if (!d.message) return monitor_.Drop(wire::ToString(d.reason), d.detail, why);
  if (auto* frame = dynamic_cast<const v1::KeypointFrame*>(d.message.get()))
    return FeedKeypoints(*frame, now_ns, why);
  if (auto* batch = dynamic_cast<const v1::ImuBatch*>(d.message.get()))
    return FeedImus(*batch, now_ns, why);
  if (auto* calibration = dynamic_cast<const v1::Calibration*>(d.message.get()))
    return FeedCalibration(*calibration, now_ns, why);
  return monitor_.Drop("not_an_input", wire::TypeName(*d.message) + " is not an input of the host",
                       why);
}

bool HostPipeline::FeedKeypoints(const v1::KeypointFrame& frame, int64_t now_ns, std::string* why) {
  int c = -1;
  Rejection rejection;
  if (!decoder_.CameraOf(frame, &c, &rejection)) {
    if (c >= 0) monitor_.camera(c).invalid++;
    return monitor_.Drop(rejection.reason, rejection.detail, why);
  }
  monitor_.camera(c).Count(frame.frame_index(), 0, frame.capture_time_ns(), now_ns);
  const bool has_subject = frame.detected() && !frame.persons().empty();
  const int subject =
      has_subject ? ChooseSubject(frame, session_.rig.cameras[c], step_.solver()) : -1;
  if (!sync_.AddCamera(decoder_.ToCameraInput(frame, c, subject), now_ns)) {
    return monitor_.Drop("late_or_duplicate",
                         frame.camera_id() + " frame " + std::to_string(frame.frame_index()), why);
  }
  return true;
}

bool HostPipeline::FeedImus(const v1::ImuBatch& batch, int64_t now_ns, std::string* why) {
  monitor_.hub(batch.hub_id()).Count(batch.sequence(), 0, batch.send_time_ns(), now_ns);
  int unknown = 0;
  for (const v1::ImuSample& s : batch.samples()) {
    const int i = decoder_.ImuOf(s.sensor_id());
    if (i < 0) {
      unknown++;
      continue;
    }
    monitor_.imu(i).Count(s.packet_counter(), 1u << 16, s.sample_time_ns(), now_ns);
    if (!sync_.AddImu(InputDecoder::ToImuInput(s, i), now_ns))
      monitor_.CountDropped("late_or_duplicate");
  }
  if (unknown == 0) return true;
  monitor_.CountDropped("unknown_source", unknown - 1);
  return monitor_.Drop("unknown_source",
                       std::to_string(unknown) + " samples of sensors not in the IMU set (hub " +
                           batch.hub_id() + ")",
                       why);
}

bool HostPipeline::FeedCalibration(const v1::Calibration& c, int64_t now_ns, std::string* why) {
  StreamStats& stats = monitor_.calibration();
  stats.received_in_period++;
  stats.latency_ms.push_back(1e-6 * static_cast<double>(now_ns - c.valid_from_ns()));
  std::string error;
  if (!calibrations_.Add(c, step_.solver(), &error))
    return monitor_.Drop("invalid_calibration", "from '" + c.source() + "': " + error, why);
  return true;
}

void HostPipeline::ApplyCalibrations(int64_t time_ns) {
  for (PendingCalibration& p : calibrations_.TakeDue(time_ns)) {
    std::string error;
    const bool ok = step_.Apply(p, &error);
    calibrations_.CountApplied(ok);
    if (!ok) {
      monitor_.CountDropped("invalid_calibration");
      continue;
    }
    session_.skeleton = std::move(p.skeleton);
    session_.layout = std::move(p.layout);
    session_.imus = std::move(p.imus);
  }
}

std::vector<SolvedFrame> HostPipeline::Solve(int64_t now_ns) {
  std::vector<SolvedFrame> out;
  for (SyncedFrame& f : sync_.TakeReady(now_ns)) {
    ApplyCalibrations(f.time_ns);
    const SolveResult r = step_.Solve(&f.observations);
    out.push_back({EncodePoseFrame(f.observations, r, f.time_ns, frames_solved_++,
                                   session_.skeleton, session_.rig, session_.imus),
                   f.last_input_ns});
    monitor_.CountSolvedFrame();
  }
  return out;
}

v1::Health HostPipeline::Health(int64_t now_ns) {
  HealthInputs in;
  in.sync = &sync_;
  in.headings = step_.solver().headings();
  in.calibrations = calibrations_.counts();
  in.calibration_active = step_.any_imu_calibrated();
  in.frames_solved = frames_solved_;
  return monitor_.Health(now_ns, in);
}

}  // namespace mocap
