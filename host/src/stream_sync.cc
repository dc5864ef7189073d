#include "mocap/stream_sync.h"

#include <algorithm>
#include <string>

namespace mocap {

bool SyncOptions::IsValid(std::string* error) const {
  if (group_tolerance_ns <= 0 || max_wait_ns < 0 || stale_after_ns <= 0 || imu_max_gap_ns <= 0 ||
      imu_max_hold_ns < 0 || imu_history_ns < imu_max_gap_ns || !(imu_only_rate_hz > 0) ||
      max_pending_frames < 1) {
    *error = "sync options out of range (tolerances and windows must be positive)";
    return false;
  }
  return true;
}

StreamSynchroniser::StreamSynchroniser(int num_cameras, int num_imus, SyncOptions options)
    : options_(options), cameras_(num_cameras), imus_(num_imus) {}

void StreamSynchroniser::MarkLinkDown(const std::vector<int>& cameras,
                                      const std::vector<int>& imus) {
  for (int c : cameras) cameras_.at(c).counts.link_down = true;
  for (int i : imus) imus_.at(i).counts.link_down = true;
}

bool StreamSynchroniser::Active(const StreamCounts& counts, int64_t now_ns) const {
  if (counts.link_down) return false;
  // A configured stream is expected from the first input of any stream on.
  const std::optional<int64_t>& last =
      counts.last_arrival_ns ? counts.last_arrival_ns : first_arrival_ns_;
  return last && now_ns - *last <= options_.stale_after_ns;
}

bool StreamSynchroniser::AddCamera(CameraInput input, int64_t now_ns) {
  CameraStream& stream = cameras_[input.camera];
  if (!first_arrival_ns_) first_arrival_ns_ = now_ns;
  stream.counts.received++;
  stream.counts.last_arrival_ns = now_ns;
  stream.counts.link_down = false;
  const int64_t t = input.time_ns;
  if (last_released_ns_ && t <= *last_released_ns_ + options_.group_tolerance_ns) {
    stream.counts.late++;
    return false;
  }
  auto it = std::find_if(pending_.begin(), pending_.end(), [&](const Group& g) {
    return std::abs(g.time_ns - t) <= options_.group_tolerance_ns;
  });
  if (it == pending_.end()) {
    Group group{t, std::vector<std::optional<CameraInput>>(cameras_.size()), now_ns};
    it = pending_.insert(std::upper_bound(pending_.begin(), pending_.end(), t,
                                          [](int64_t v, const Group& g) { return v < g.time_ns; }),
                         std::move(group));
  } else if (it->cameras[input.camera]) {
    stream.counts.duplicates++;
    return false;
  }
  if (stream.newest_ns && t < *stream.newest_ns) stream.counts.out_of_order++;
  stream.newest_ns = std::max(stream.newest_ns.value_or(t), t);
  it->last_input_ns = std::max(it->last_input_ns, now_ns);
  const int c = input.camera;
  it->cameras[c] = std::move(input);
  return true;
}

bool StreamSynchroniser::AddImu(const ImuInput& input, int64_t now_ns) {
  ImuStream& stream = imus_[input.imu];
  if (!first_arrival_ns_) first_arrival_ns_ = now_ns;
  stream.counts.received++;
  stream.counts.last_arrival_ns = now_ns;
  stream.counts.link_down = false;
  auto& samples = stream.samples;
  const int64_t t = input.time_ns;
  auto at = std::lower_bound(samples.begin(), samples.end(), t,
                             [](const Sample& s, int64_t v) { return s.input.time_ns < v; });
  if (at != samples.end() && at->input.time_ns == t) {
    stream.counts.duplicates++;
    return false;
  }
  if (at != samples.end()) stream.counts.out_of_order++;
  // A sample older than what the released frames could still use is of no use.
  if (last_released_ns_ && t < *last_released_ns_ - options_.imu_max_gap_ns) {
    stream.counts.late++;
    return false;
  }
  samples.insert(at, Sample{input, now_ns});
  const int64_t keep_from = samples.back().input.time_ns - options_.imu_history_ns;
  while (samples.size() > 2 && samples.front().input.time_ns < keep_from) samples.pop_front();
  return true;
}

bool StreamSynchroniser::Complete(const Group& group, int64_t now_ns) const {
  for (size_t c = 0; c < cameras_.size(); ++c) {
    if (group.cameras[c] || !Active(cameras_[c].counts, now_ns)) continue;
    const auto& newest = cameras_[c].newest_ns;
    if (!newest || *newest <= group.time_ns + options_.group_tolerance_ns) return false;
  }
  for (const ImuStream& imu : imus_) {
    if (!Active(imu.counts, now_ns)) continue;
    if (imu.samples.empty() || imu.samples.back().input.time_ns < group.time_ns) return false;
  }
  return true;
}

void StreamSynchroniser::ClockFromImus(int64_t now_ns) {
  for (size_t c = 0; c < cameras_.size(); ++c) {
    if (Active(cameras_[c].counts, now_ns)) return;
  }
  std::optional<int64_t> newest, first;
  for (const ImuStream& imu : imus_) {
    if (!Active(imu.counts, now_ns) || imu.samples.empty()) continue;
    newest = std::max(newest.value_or(INT64_MIN), imu.samples.back().input.time_ns);
    first = std::min(first.value_or(INT64_MAX), imu.samples.front().input.time_ns);
  }
  if (!newest) return;
  const auto period = static_cast<int64_t>(1e9 / options_.imu_only_rate_hz);
  int64_t t = !pending_.empty()   ? pending_.back().time_ns + period
              : last_released_ns_ ? *last_released_ns_ + period
                                  : *first;
  t = std::max(t, *newest - options_.max_wait_ns - period);  // after a long pause: no backlog
  for (; t <= *newest; t += period) {
    pending_.push_back(Group{t, std::vector<std::optional<CameraInput>>(cameras_.size()), now_ns});
  }
}

std::vector<SyncedFrame> StreamSynchroniser::TakeReady(int64_t now_ns) {
  ClockFromImus(now_ns);
  return TakePending(now_ns, /*all=*/false);
}

std::vector<SyncedFrame> StreamSynchroniser::Flush() {
  std::optional<int64_t> newest;
  const auto later = [&](const StreamCounts& c) {
    if (c.last_arrival_ns) newest = std::max(newest.value_or(INT64_MIN), *c.last_arrival_ns);
  };
  for (const CameraStream& c : cameras_) later(c.counts);
  for (const ImuStream& i : imus_) later(i.counts);
  if (!newest) return {};
  const int64_t now_ns = *newest + options_.max_wait_ns;
  ClockFromImus(now_ns);
  return TakePending(now_ns, /*all=*/true);
}

std::vector<SyncedFrame> StreamSynchroniser::TakePending(int64_t now_ns, bool all) {
  std::vector<SyncedFrame> ready;
  while (!pending_.empty()) {
    const Group& front = pending_.front();
    const bool overflow = static_cast<int>(pending_.size()) > options_.max_pending_frames;
    const bool deadline = now_ns >= front.time_ns + options_.max_wait_ns;
    const bool complete = Complete(front, now_ns);
    if (!complete && !deadline && !overflow && !all) break;
    if (!complete) frames_forced_++;
    Group group = std::move(pending_.front());
    pending_.pop_front();
    ready.push_back(Release(std::move(group), now_ns));
  }
  return ready;
}

SyncedFrame StreamSynchroniser::Release(Group group, int64_t now_ns) {
  if (!epoch_ns_) epoch_ns_ = group.time_ns;
  last_released_ns_ = group.time_ns;
  frames_released_++;
  SyncedFrame out;
  out.time_ns = group.time_ns;
  out.released_ns = now_ns;
  out.last_input_ns = group.last_input_ns;
  out.observations.timestamp = 1e-9 * static_cast<double>(group.time_ns - *epoch_ns_);
  for (size_t c = 0; c < group.cameras.size(); ++c) {
    if (!group.cameras[c]) continue;
    out.cameras_clocked.push_back(static_cast<int>(c));
    CameraInput& in = *group.cameras[c];
    if (in.detected) out.cameras_detected.push_back(static_cast<int>(c));
    if (in.detected && !in.keypoints.empty()) {
      out.observations.cameras.push_back(CameraObservation{in.camera, std::move(in.keypoints)});
    }
    if (in.detected)
      for (std::vector<Keypoint2D>& person : in.persons)
        out.people.push_back(CameraObservation{in.camera, std::move(person)});
  }
  for (size_t i = 0; i < imus_.size(); ++i) {
    if (auto reading = Interpolate(static_cast<int>(i), group.time_ns)) {
      out.observations.imus.push_back(reading->first);
      out.last_input_ns = std::max(out.last_input_ns, reading->second);
    }
    // Keep one sample before the released time for the next frame's interpolation.
    auto& samples = imus_[i].samples;
    while (samples.size() > 1 && samples[1].input.time_ns <= group.time_ns) samples.pop_front();
  }
  return out;
}

std::optional<std::pair<ImuObservation, int64_t>> StreamSynchroniser::Interpolate(int i,
                                                                                  int64_t t) const {
  const auto& samples = imus_[i].samples;
  auto after = std::lower_bound(samples.begin(), samples.end(), t,
                                [](const Sample& s, int64_t v) { return s.input.time_ns < v; });
  const Sample* s1 = after != samples.end() ? &*after : nullptr;
  const Sample* s0 = after != samples.begin() ? &*(after - 1) : nullptr;
  auto from = [&](const Sample& s) {
    ImuObservation o;
    o.imu = i;
    o.orientation = s.input.orientation;
    o.acceleration = s.input.acceleration;
    o.has_orientation = s.input.has_orientation;
    o.has_acceleration = s.input.has_acceleration;
    return o;
  };
  if (s1 && s1->input.time_ns == t) return std::make_pair(from(*s1), s1->arrival_ns);
  if (s0 && s1 && s1->input.time_ns - s0->input.time_ns <= options_.imu_max_gap_ns) {
    const double w = static_cast<double>(t - s0->input.time_ns) /
                     static_cast<double>(s1->input.time_ns - s0->input.time_ns);
    ImuObservation o = from(*s0);
    o.orientation = s0->input.orientation.slerp(w, s1->input.orientation);
    o.acceleration = (1 - w) * s0->input.acceleration + w * s1->input.acceleration;
    o.has_orientation = s0->input.has_orientation && s1->input.has_orientation;
    o.has_acceleration = s0->input.has_acceleration && s1->input.has_acceleration;
    return std::make_pair(o, std::max(s0->arrival_ns, s1->arrival_ns));
  }
  if (s0 && t - s0->input.time_ns <= options_.imu_max_hold_ns)
    return std::make_pair(from(*s0), s0->arrival_ns);
  if (s1 && s1->input.time_ns - t <= options_.imu_max_hold_ns)
    return std::make_pair(from(*s1), s1->arrival_ns);
  return std::nullopt;
}

}  // namespace mocap
