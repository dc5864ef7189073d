#include "pipeline.h"

#include <algorithm>

#include "pose_frame_encoder.h"
#include "wire.h"

namespace mocap {

std::unique_ptr<HostPipeline> HostPipeline::Create(Session session, std::string* error) {
  auto solver = Solver::Create(session.skeleton, session.rig, session.layout, session.imus,
                               session.prior, session.solver, error);
  if (!solver) return nullptr;
  return std::unique_ptr<HostPipeline>(new HostPipeline(std::move(session), std::move(solver)));
}

HostPipeline::HostPipeline(Session session, std::unique_ptr<Solver> solver)
    : session_(std::move(session)),
      step_(std::move(solver), session_.imus_calibrated),
      input_(session_.rig, session_.imus, session_.layout, session_.sync,
             session_.solver.min_confidence, session_.people > 1) {
  if (session_.people <= 1) return;
  TrackerOptions options;
  options.max_subjects = session_.people;
  options.min_confidence = session_.solver.min_confidence;
  const Session& s = session_;
  std::vector<SuitCalibration> suits;
  suit_of_.assign(s.imus.size(), {-1, -1});
  for (size_t k = 0; k < s.suits.size(); ++k) {
    suits.push_back(s.suits[k].calibration);
    for (size_t i = 0; i < s.suits[k].sensors.size(); ++i)
      suit_of_[s.suits[k].sensors[i]] = {static_cast<int>(k), static_cast<int>(i)};
  }
  tracker_ = std::make_unique<SubjectTracker>(
      [skeleton = s.skeleton, rig = s.rig, layout = s.layout, prior = s.prior, solver = s.solver] {
        std::string ignored;  // the session's solver was made from the same: it cannot fail
        return Solver::Create(skeleton, rig, layout, {}, prior, solver, &ignored);
      },
      options, suits);
}

bool HostPipeline::Feed(std::string_view type, std::string_view payload, int64_t now_ns,
                        std::string* why, int link) {
  wire::Decoded d = wire::DecodeMessage(type, payload);
  if (!d.message) return input_.monitor().Drop(wire::ToString(d.reason), d.detail, why);
  if (auto* calibration = dynamic_cast<const v1::Calibration*>(d.message.get()))
    return FeedCalibration(*calibration, now_ns, why);
  if (auto* report = dynamic_cast<const v1::Health*>(d.message.get())) {
    if (edge_health_.Add(*report, now_ns)) return true;
    return input_.monitor().Drop("invalid", "a Health report without its source", why);
  }
  return input_.Feed(*d.message, now_ns, &step_.solver(), why, link);
}

bool HostPipeline::FeedCalibration(const v1::Calibration& c, int64_t now_ns, std::string* why) {
  StreamStats& stats = input_.monitor().calibration();
  stats.received_in_period++;
  stats.latency_ms.push_back(
      1e-6 * (static_cast<double>(now_ns) - static_cast<double>(c.valid_from_ns())));
  std::string error;
  if (!calibrations_.Add(c, step_.solver(), &error))
    return input_.monitor().Drop("invalid_calibration", "from '" + c.source() + "': " + error, why);
  return true;
}

void HostPipeline::ApplyCalibrations(int64_t time_ns) {
  for (PendingCalibration& p : calibrations_.TakeDue(time_ns)) {
    std::string error;
    const bool ok = step_.Apply(p, &error);
    calibrations_.CountApplied(ok);
    if (!ok) {
      input_.monitor().CountDropped("invalid_calibration");
      continue;
    }
    session_.skeleton = std::move(p.skeleton);
    session_.layout = std::move(p.layout);
    session_.imus = std::move(p.imus);
  }
}

std::vector<SolvedFrame> HostPipeline::Solve(int64_t now_ns) {
  return SolveFrames(input_.TakeReady(now_ns));
}

std::vector<SolvedFrame> HostPipeline::Flush() { return SolveFrames(input_.Flush()); }

std::vector<SolvedFrame> HostPipeline::SolveFrames(std::vector<SyncedFrame> frames) {
  std::vector<SolvedFrame> out;
  for (SyncedFrame& f : frames) {
    if (tracker_) {
      SolvePeople(f, &out);
      continue;
    }
    ApplyCalibrations(f.time_ns);
    const SolveResult r = step_.Solve(&f.observations);
    frames_failed_ += r.status == SolveStatus::kFailed;
    out.push_back({EncodePoseFrame(f.observations, r, f.time_ns, frames_solved_++,
                                   session_.skeleton, session_.rig, session_.imus),
                   f.last_input_ns});
    input_.monitor().CountSolvedFrame();
  }
  return out;
}

// One PoseFrame per person seen in the frame, each with its subject id and the frame's index.
void HostPipeline::SolvePeople(const SyncedFrame& f, std::vector<SolvedFrame>* out) {
  const uint64_t index = frames_solved_++;
  std::vector<std::vector<ImuObservation>> suits(session_.suits.size());  // each suit's readings
  for (ImuObservation o : f.observations.imus) {
    const auto [suit, sensor] = suit_of_[o.imu];
    if (suit < 0) continue;  // a sensor of no suit
    o.imu = sensor;
    suits[suit].push_back(o);
  }
  for (const SubjectFrame& s :
       tracker_->Track(f.observations.timestamp, f.people, nullptr, suits)) {
    if (s.cameras.empty() && s.suit < 0) continue;  // not seen this frame: nothing new
    FrameObservations used;
    for (int c : s.cameras) used.cameras.push_back(CameraObservation{c, {}});
    const SuitCalibration* suit = s.suit >= 0 ? &session_.suits[s.suit].calibration : nullptr;
    if (suit) used.imus = suits[s.suit];
    const Skeleton& skeleton =  // the solve's: a suit's before it is decided, as its leader's
        s.skeleton >= 0 ? session_.suits[s.skeleton].calibration.skeleton : session_.skeleton;
    frames_failed_ += s.result.status == SolveStatus::kFailed;
    v1::PoseFrame pose = EncodePoseFrame(used, s.result, f.time_ns, index, skeleton, session_.rig,
                                         suit ? suit->imus : std::vector<ImuSite>());
    pose.set_subject_id(s.id);
    out->push_back({std::move(pose), f.last_input_ns});
  }
  input_.monitor().CountSolvedFrame();
}

v1::Health HostPipeline::Health(int64_t now_ns) {
  HealthInputs in;
  in.sync = &input_.sync();
  in.headings = step_.solver().headings();
  for (size_t i = 0; i < in.headings.size(); ++i)
    in.distrusted.push_back(step_.solver().distrusted(static_cast<int>(i)));
  in.calibrations = calibrations_.counts();
  in.calibration_active = step_.any_imu_calibrated();
  in.frames_solved = frames_solved_;
  in.frames_failed = frames_failed_;
  v1::Health health = input_.monitor().Health(now_ns, in);
  if (tracker_) {
    const TrackerCounts& c = tracker_->counts();
    v1::People* people = health.mutable_people();
    people->set_tracked(tracker_->tracked());
    people->set_born(c.births);
    people->set_retired(c.retired);
    people->set_found_again(c.revivals);
    people->set_views_dropped(c.people_dropped);
    people->set_views_unexplained(c.views_unexplained);
    people->set_suits_worn(static_cast<uint32_t>(std::count_if(
        tracker_->wearers().begin(), tracker_->wearers().end(), [](uint32_t id) { return id; })));
    people->set_suit_changes(c.suit_changes);
    people->set_suits_doubted(c.suits_doubted);
  }
  edge_health_.AppendTo(now_ns, &health);
  return health;
}

}  // namespace mocap
