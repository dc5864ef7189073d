#include "pipeline.h"

#include <algorithm>
#include <cmath>

#include "mocap/kinematics.h"

namespace mocap {
namespace {

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(p * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

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

}  // namespace

std::unique_ptr<HostPipeline> HostPipeline::Create(Session session, std::string* error) {
  auto solver = Solver::Create(session.skeleton, session.rig, session.layout, session.imus,
                               session.prior, session.solver, error);
  if (!solver) return nullptr;
  return std::unique_ptr<HostPipeline>(new HostPipeline(std::move(session), std::move(solver)));
}

HostPipeline::HostPipeline(Session session, std::unique_ptr<Solver> solver)
    : session_(std::move(session)),
      solver_(std::move(solver)),
      sync_(static_cast<int>(session_.rig.cameras.size()), static_cast<int>(session_.imus.size()),
            session_.sync),
      imu_calibrated_(session_.imus.size(), session_.imus_calibrated),
      camera_stats_(session_.rig.cameras.size()),
      imu_stats_(session_.imus.size()) {
  for (size_t c = 0; c < session_.rig.cameras.size(); ++c)
    camera_index_[session_.rig.cameras[c].name] = c;
  for (size_t i = 0; i < session_.imus.size(); ++i) imu_index_[session_.imus[i].name] = i;
}

bool HostPipeline::Drop(const std::string& reason, const std::string& detail, std::string* why) {
  dropped_[reason]++;
  if (why) *why = reason + ": " + detail;
  return false;
}

void HostPipeline::Count(StreamStats* stats, uint64_t counter, uint64_t modulo, int64_t time_ns,
                         int64_t now_ns) {
  constexpr uint64_t kLargestGap = 1u << 20;  // a jump this far ahead is a restart, not a loss
  stats->received_in_period++;
  stats->latency_ms.push_back(1e-6 * static_cast<double>(now_ns - time_ns));
  if (!stats->last_counter) {
    stats->last_counter = counter;
    stats->last_time_ns = time_ns;
    return;
  }
  const uint64_t last = *stats->last_counter;
  const uint64_t ahead = modulo ? (counter + modulo - last) % modulo : counter - last;
  const bool forward = modulo ? ahead != 0 && ahead < modulo / 2 : counter > last;
  if (forward) {
    if (ahead > 1 && ahead < kLargestGap) stats->lost += ahead - 1;
  } else if (time_ns <= stats->last_time_ns) {
    if (stats->lost > 0) stats->lost--;  // a late message, counted lost when it was skipped
    return;
  }  // else: newer but counted back: the sender restarted its counter
  stats->last_counter = counter;
  stats->last_time_ns = time_ns;
}

bool HostPipeline::Feed(std::string_view type, std::string_view payload, int64_t now_ns,
                        std::string* why) {
  wire::Decoded d = wire::DecodeMessage(type, payload);
  if (!d.message) return Drop(wire::ToString(d.reason), d.detail, why);
  if (auto* frame = dynamic_cast<const v1::KeypointFrame*>(d.message.get()))
    return FeedKeypoints(*frame, now_ns, why);
  if (auto* batch = dynamic_cast<const v1::ImuBatch*>(d.message.get()))
    return FeedImus(*batch, now_ns, why);
  if (auto* calibration = dynamic_cast<const v1::Calibration*>(d.message.get())) {
    calibration_stats_.received_in_period++;
    calibration_stats_.latency_ms.push_back(
        1e-6 * static_cast<double>(now_ns - calibration->valid_from_ns()));
    return FeedCalibration(*calibration, why);
  }
  return Drop("not_an_input", wire::TypeName(*d.message) + " is not an input of the host", why);
}

bool HostPipeline::FeedKeypoints(const v1::KeypointFrame& frame, int64_t now_ns, std::string* why) {
  const auto it = camera_index_.find(frame.camera_id());
  if (it == camera_index_.end())
    return Drop("unknown_source", "camera '" + frame.camera_id() + "' is not in the rig", why);
  const int c = it->second;
  StreamStats& stats = camera_stats_[c];
  const int n = session_.layout.size();
  const bool wrong_layout = frame.detected() && !frame.persons().empty() &&
                            frame.keypoint_layout() != session_.layout.name;
  const bool wrong_size = std::any_of(frame.persons().begin(), frame.persons().end(),
                                      [&](const v1::KeypointPerson& p) { return p.x_size() != n; });
  if (wrong_layout || (frame.detected() && wrong_size)) {
    stats.invalid++;
    return Drop("invalid",
                frame.camera_id() + ": layout '" + frame.keypoint_layout() +
                    "' or keypoint count is not the session's " + session_.layout.name + " (" +
                    std::to_string(n) + ")",
                why);
  }
  Count(&stats, frame.frame_index(), 0, frame.capture_time_ns(), now_ns);
  CameraInput in;
  in.camera = c;
  in.time_ns = frame.capture_time_ns();
  in.detected = frame.detected();
  if (frame.detected() && !frame.persons().empty()) {
    const v1::KeypointPerson& p = frame.persons(ChooseSubject(frame, c));
    in.keypoints.resize(n);
    for (int k = 0; k < n; ++k) in.keypoints[k] = Keypoint2D{p.x(k), p.y(k), p.confidence(k)};
  }
  if (!sync_.AddCamera(std::move(in), now_ns)) {
    return Drop("late_or_duplicate",
                frame.camera_id() + " frame " + std::to_string(frame.frame_index()), why);
  }
  return true;
}

bool HostPipeline::FeedImus(const v1::ImuBatch& batch, int64_t now_ns, std::string* why) {
  Count(&hub_stats_[batch.hub_id()], batch.sequence(), 0, batch.send_time_ns(), now_ns);
  int unknown = 0;
  for (const v1::ImuSample& s : batch.samples()) {
    const auto it = imu_index_.find(s.sensor_id());
    if (it == imu_index_.end()) {
      unknown++;
      continue;
    }
    Count(&imu_stats_[it->second], s.packet_counter(), 1u << 16, s.sample_time_ns(), now_ns);
    ImuInput in;
    in.imu = it->second;
    in.time_ns = s.sample_time_ns();
    in.orientation = Eigen::Quaterniond(s.qw(), s.qx(), s.qy(), s.qz());
    in.acceleration = {s.ax(), s.ay(), s.az()};
    in.has_orientation = !(s.status() & v1::ImuSample::STATUS_ORIENTATION_INVALID);
    in.has_acceleration = !(s.status() & v1::ImuSample::STATUS_ACCELERATION_INVALID);
    if (!sync_.AddImu(in, now_ns)) dropped_["late_or_duplicate"]++;
  }
  if (unknown) {
    dropped_["unknown_source"] += unknown - 1;
    return Drop("unknown_source",
                std::to_string(unknown) + " samples of sensors not in the IMU set (hub " +
                    batch.hub_id() + ")",
                why);
  }
  return true;
}

bool HostPipeline::FeedCalibration(const v1::Calibration& c, std::string* why) {
  const auto reject = [&](const std::string& detail) {
    calibrations_rejected_++;
    return Drop("invalid_calibration", "from '" + c.source() + "': " + detail, why);
  };
  const auto seen = calibration_sequences_.find(c.source());
  if (seen != calibration_sequences_.end() && c.sequence() <= seen->second) {
    calibrations_repeated_++;
    return true;  // taken already
  }
  PendingCalibration p;
  p.valid_from_ns = c.valid_from_ns();
  std::string error;
  if (!ParseSkeletonJson(c.skeleton_json(), &p.skeleton, &error)) return reject(error);
  const Skeleton& ours = session_.skeleton;
  if (p.skeleton.num_bones() != ours.num_bones()) return reject("other bones than the session's");
  for (int b = 0; b < ours.num_bones(); ++b) {
    if (p.skeleton.bone(b).name != ours.bone(b).name ||
        p.skeleton.bone(b).parent != ours.bone(b).parent)
      return reject("other bones than the session's (bone '" + p.skeleton.bone(b).name + "')");
  }
  KeypointLayout layout;
  if (!ParseKeypointLayoutJson(c.layout_json(), p.skeleton, &layout, &error)) return reject(error);
  if (layout.name != session_.layout.name || layout.names != session_.layout.names)
    return reject("layout '" + layout.name + "' is not the session's " + session_.layout.name);
  p.layout = layout.ScaledTo(p.skeleton);
  std::vector<ImuSite> sites;
  if (!ParseImuSitesJson(c.imus_json(), p.skeleton, &sites, &error)) return reject(error);
  p.imus = solver_->imus();  // sensors the calibration leaves out keep their place, unused
  p.calibrated.assign(p.imus.size(), false);
  for (ImuSite& site : sites) {
    const auto it = imu_index_.find(site.name);
    if (it == imu_index_.end()) return reject("sensor '" + site.name + "' is not in the IMU set");
    p.calibrated[it->second] = true;
    p.imus[it->second] = std::move(site);
  }
  const auto at =
      std::upper_bound(pending_.begin(), pending_.end(), p.valid_from_ns,
                       [](int64_t t, const PendingCalibration& q) { return t < q.valid_from_ns; });
  pending_.insert(at, std::move(p));
  calibration_sequences_[c.source()] = c.sequence();
  return true;
}

void HostPipeline::ApplyCalibrations(int64_t time_ns) {
  while (!pending_.empty() && pending_.front().valid_from_ns <= time_ns) {
    PendingCalibration& p = pending_.front();
    std::string error;
    if (solver_->SetCalibration(p.skeleton, p.layout, p.imus, &error)) {
      session_.skeleton = std::move(p.skeleton);
      session_.layout = std::move(p.layout);
      session_.imus = std::move(p.imus);
      imu_calibrated_ = std::move(p.calibrated);
      calibrations_applied_++;
    } else {
      calibrations_rejected_++;
      dropped_["invalid_calibration"]++;
    }
    pending_.erase(pending_.begin());
  }
}

int HostPipeline::ChooseSubject(const v1::KeypointFrame& frame, int camera) const {
  const double min_conf = session_.solver.min_confidence;
  std::vector<Eigen::Vector2d> predicted;
  if (solver_->initialised() && frame.persons_size() > 1) {
    BodyPose pose;
    ForwardKinematics(session_.skeleton, solver_->pose().data(), &pose);
    for (const Site& s : session_.layout.sites) {
      Eigen::Vector2d px(NAN, NAN);
      session_.rig.cameras[camera].Project(pose.position[s.bone] + pose.rotation[s.bone] * s.offset,
                                           &px);
      predicted.push_back(px);
    }
  }
  int best = 0;
  double best_score = predicted.empty() ? -1 : INFINITY;
  for (int p = 0; p < frame.persons_size(); ++p) {
    const v1::KeypointPerson& person = frame.persons(p);
    if (predicted.empty()) {  // most confident
      double sum = 0;
      for (float c : person.confidence()) sum += c;
      if (sum > best_score) best_score = sum, best = p;
      continue;
    }
    std::vector<double> d;  // median distance to the projection of the tracked pose
    for (int k = 0; k < person.x_size(); ++k) {
      if (person.confidence(k) > min_conf && predicted[k].allFinite()) {
        d.push_back((Eigen::Vector2d(person.x(k), person.y(k)) - predicted[k]).norm());
      }
    }
    const double score = d.empty() ? INFINITY : Percentile(d, 0.5);
    if (score < best_score) best_score = score, best = p;
  }
  return best;
}

std::vector<SolvedFrame> HostPipeline::Solve(int64_t now_ns) {
  std::vector<SolvedFrame> out;
  for (SyncedFrame& f : sync_.TakeReady(now_ns)) {
    ApplyCalibrations(f.time_ns);
    std::vector<ImuObservation>& imus =
        f.observations.imus;  // only calibrated IMUs are solved with
    imus.erase(std::remove_if(imus.begin(), imus.end(),
                              [&](const ImuObservation& i) { return !imu_calibrated_[i.imu]; }),
               imus.end());
    const SolveResult r = solver_->Solve(f.observations);
    SolvedFrame s;
    s.last_input_ns = f.last_input_ns;
    v1::PoseFrame& p = s.pose;
    p.set_capture_time_ns(f.time_ns);
    p.set_frame_index(frames_solved_++);
    p.set_status(ToProto(r.status));
    for (int i = 0; i < r.theta.size(); ++i) p.add_theta(r.theta[i]);
    BodyPose pose;
    ForwardKinematics(session_.skeleton, r.theta.data(), &pose);
    for (int b = 0; b < session_.skeleton.num_bones(); ++b) {
      v1::JointTransform* j = p.add_joints();
      const Eigen::Quaterniond q(pose.rotation[b]);
      j->set_name(session_.skeleton.bone(b).name);
      j->set_px(pose.position[b].x()), j->set_py(pose.position[b].y()),
          j->set_pz(pose.position[b].z());
      j->set_qw(q.w()), j->set_qx(q.x()), j->set_qy(q.y()), j->set_qz(q.z());
    }
    v1::TermCosts* costs = p.mutable_costs();
    costs->set_orientation(r.costs.orientation);
    costs->set_position(r.costs.position);
    costs->set_acceleration(r.costs.acceleration);
    costs->set_pca_projection(r.costs.pca_projection);
    costs->set_pca_deviation(r.costs.pca_deviation);
    p.set_iterations(r.iterations);
    p.set_solve_time_ms(r.solve_time_ms);
    p.set_quality_flags(r.flags);
    for (const CameraObservation& c : f.observations.cameras)
      p.add_cameras(session_.rig.cameras[c.camera].name);
    for (const ImuObservation& i : f.observations.imus) p.add_imus(session_.imus[i.imu].name);
    frames_in_period_++;
    out.push_back(std::move(s));
  }
  return out;
}

v1::Health HostPipeline::Health(int64_t now_ns) {
  const double period_s =
      period_start_ns_ ? std::max(1e-3, 1e-9 * static_cast<double>(now_ns - *period_start_ns_))
                       : 1.0;
  period_start_ns_ = now_ns;
  v1::Health h;
  h.set_source("host");
  h.set_time_ns(now_ns);
  // repeats_drop: a duplicate is a lost message (not for calibrations: repeated by design).
  const auto add = [&](const std::string& name, bool active, StreamStats& st,
                       const StreamCounts* counts, bool repeats_drop = true) {
    v1::StreamHealth* s = h.add_streams();
    s->set_stream(name);
    s->set_active(active);
    s->set_rate_hz(static_cast<double>(st.received_in_period) / period_s);
    s->set_lost(st.lost);
    s->set_latency_p50_ms(Percentile(st.latency_ms, 0.5));
    s->set_latency_p99_ms(Percentile(st.latency_ms, 0.99));
    if (counts) {
      s->set_received(counts->received);
      s->set_late(counts->late);
      s->set_duplicates(counts->duplicates);
    }
    s->set_malformed(st.invalid);
    s->set_dropped(s->late() + (repeats_drop ? s->duplicates() : 0) + s->malformed());
    st.received_in_period = 0;
    st.latency_ms.clear();
  };
  for (size_t c = 0; c < camera_stats_.size(); ++c) {
    add("camera/" + session_.rig.cameras[c].name, sync_.CameraActive(c, now_ns), camera_stats_[c],
        &sync_.camera_counts(c));
  }
  for (size_t i = 0; i < imu_stats_.size(); ++i) {
    add("imu/" + session_.imus[i].name, sync_.ImuActive(i, now_ns), imu_stats_[i],
        &sync_.imu_counts(i));
    h.mutable_streams(h.streams_size() - 1)
        ->set_heading_correction_deg(solver_->headings()[i] * 180.0 / M_PI);
  }
  for (auto& [hub, stats] : hub_stats_)
    add("hub/" + hub, stats.received_in_period > 0, stats, nullptr);
  // Calibrations: received in the period (rate), applied since start (received), repeats of
  // one taken (duplicates: the calibrator repeats the latest for hosts that start later, so
  // not dropped), rejected (malformed = dropped); active while any IMU is solved with;
  // latency = arrival - valid_from.
  calibration_stats_.invalid = calibrations_rejected_;
  StreamCounts applied;
  applied.received = calibrations_applied_;
  applied.duplicates = calibrations_repeated_;
  add("calibration",
      std::find(imu_calibrated_.begin(), imu_calibrated_.end(), true) != imu_calibrated_.end(),
      calibration_stats_, &applied, /*repeats_drop=*/false);
  uint64_t malformed = 0;
  for (const auto& [reason, n] : dropped_)  // those two are counted by their streams above
    malformed += reason == "late_or_duplicate" || reason == "invalid_calibration" ? 0 : n;
  StreamStats input;
  input.invalid = malformed;
  add("input", true, input, nullptr);  // every message dropped before reaching a stream
  h.set_latency_p50_ms(Percentile(latencies_ms_, 0.5));
  h.set_latency_p99_ms(Percentile(latencies_ms_, 0.99));
  latencies_ms_.clear();
  h.set_frames_solved(frames_solved_);
  // frames_dropped stays 0: the synchroniser hands over every frame it was given (a
  // frame released with a stream missing is counted as the pose stream's "late").
  v1::StreamHealth* pose = h.add_streams();
  pose->set_stream("pose");
  pose->set_active(frames_in_period_ > 0);
  pose->set_rate_hz(static_cast<double>(frames_in_period_) / period_s);
  pose->set_received(frames_solved_);
  pose->set_late(sync_.frames_forced());  // released by deadline with a stream missing
  frames_in_period_ = 0;
  return h;
}

}  // namespace mocap
