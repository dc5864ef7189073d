#include "stream_monitor.h"

#include <algorithm>
#include <cmath>

namespace mocap {

StreamMonitor::StreamMonitor(std::vector<std::string> cameras, std::vector<std::string> imus)
    : camera_names_(std::move(cameras)),
      imu_names_(std::move(imus)),
      cameras_(camera_names_.size()),
      imus_(imu_names_.size()) {}

bool StreamMonitor::Drop(const std::string& reason, const std::string& detail, std::string* why) {
  dropped_[reason]++;
  if (why) *why = reason + ": " + detail;
  return false;
}

void StreamMonitor::AddStream(const std::string& name, bool active, const StreamCounts* counts,
                              bool repeats_drop, StreamStats* st, v1::Health* h) const {
  v1::StreamHealth* s = h->add_streams();
  s->set_stream(name);
  s->set_active(active);
  s->set_rate_hz(static_cast<double>(st->received_in_period) / period_s_);
  s->set_lost(st->lost);
  s->set_latency_p50_ms(Percentile(st->latency_ms, 0.5));
  s->set_latency_p99_ms(Percentile(st->latency_ms, 0.99));
  if (counts) {
    s->set_received(counts->received);
    s->set_late(counts->late);
    s->set_duplicates(counts->duplicates);
  }
  s->set_malformed(st->invalid);
  s->set_clock_steps(st->clock.steps());
  s->set_dropped(s->late() + (repeats_drop ? s->duplicates() : 0) + s->malformed() +
                 st->clock.dropped());
  st->received_in_period = 0;
  st->latency_ms.clear();
}

v1::Health StreamMonitor::Health(int64_t now_ns, const HealthInputs& in) {
  period_s_ = period_start_ns_
                  ? std::max(1e-3, 1e-9 * static_cast<double>(now_ns - *period_start_ns_))
                  : 1.0;
  period_start_ns_ = now_ns;
  v1::Health h;
  h.set_source("host");
  h.set_time_ns(now_ns);
  for (size_t c = 0; c < cameras_.size(); ++c) {
    AddStream("camera/" + camera_names_[c], in.sync->CameraActive(c, now_ns),
              &in.sync->camera_counts(c), true, &cameras_[c], &h);
  }
  for (size_t i = 0; i < imus_.size(); ++i) {
    AddStream("imu/" + imu_names_[i], in.sync->ImuActive(i, now_ns), &in.sync->imu_counts(i), true,
              &imus_[i], &h);
    v1::StreamHealth* imu = h.mutable_streams(h.streams_size() - 1);
    imu->set_heading_correction_deg(in.headings[i] * 180 / M_PI);
    imu->set_distrusted(i < in.distrusted.size() && in.distrusted[i]);
  }
  for (auto& [hub, stats] : hubs_)
    AddStream("hub/" + hub, stats.received_in_period > 0, nullptr, true, &stats, &h);
  AddCalibration(in, &h);
  AddInputAndPose(in, &h);
  return h;
}

// Calibrations: received in the period (rate), applied since start (received), repeats of
// one taken (duplicates: the calibrator repeats the latest for hosts that start later, so
// not dropped), rejected (malformed = dropped); active while any IMU is solved with;
// latency = arrival - valid_from.
void StreamMonitor::AddCalibration(const HealthInputs& in, v1::Health* h) {
  calibration_.invalid = in.calibrations.rejected;
  StreamCounts applied;
  applied.received = in.calibrations.applied;
  applied.duplicates = in.calibrations.repeated;
  AddStream("calibration", in.calibration_active, &applied, /*repeats_drop=*/false, &calibration_,
            h);
}

// "input": every message dropped before it reached a stream; "pose": the frames solved.
void StreamMonitor::AddInputAndPose(const HealthInputs& in, v1::Health* h) {
  StreamStats input;
  for (const auto& [reason, n] : dropped_)  // those three are counted by their streams
    input.invalid +=
        reason == "late_or_duplicate" || reason == "invalid_calibration" || reason == "clock_step"
            ? 0
            : n;
  AddStream("input", true, nullptr, true, &input, h);
  h->set_latency_p50_ms(Percentile(latencies_ms_, 0.5));
  h->set_latency_p99_ms(Percentile(latencies_ms_, 0.99));
  latencies_ms_.clear();
  h->set_frames_solved(in.frames_solved);
  // frames_dropped: the frames the solver refused (status FAILED: a failed optimisation, a pose
  // no camera's view supports), published with the previous pose held. The synchroniser hands
  // over every frame it was given (one released with a stream missing is the pose's "late").
  h->set_frames_dropped(in.frames_failed);
  v1::StreamHealth* pose = h->add_streams();
  pose->set_stream("pose");
  pose->set_active(frames_in_period_ > 0);
  pose->set_rate_hz(static_cast<double>(frames_in_period_) / period_s_);
  pose->set_received(in.frames_solved);
  pose->set_late(in.sync->frames_forced());  // released by deadline with a stream missing
  frames_in_period_ = 0;
}

}  // namespace mocap
