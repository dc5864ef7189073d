#include "input_path.h"

#include "wire.h"

namespace mocap {
namespace {

template <typename T>
std::vector<std::string> Names(const std::vector<T>& items) {
  std::vector<std::string> names;
  for (const T& item : items) names.push_back(item.name);
  return names;
}

// An input whose time is this far from its arrival is on another clock: edge clocks follow
// the host's to well under a millisecond and an input's latency is tens of milliseconds; a
// loaded machine's start-up burst arrives ~1.1 s late (tests/test_live.py on 2 busy cores),
// and is late, not on another clock. The synchroniser's deadlines (max_wait, 25 ms) compare the
// two times: mixed, every frame is released on its first camera, the others dropped as late,
// and one camera's depth guess is solved (a recording replayed without --restamp).
constexpr int64_t kMaxClockOffsetNs = 10'000'000'000;

bool OffClock(int64_t time_ns, int64_t now_ns) {
  int64_t offset;  // a time from anywhere in int64's range (a broken sender) must not overflow
  if (__builtin_sub_overflow(now_ns, time_ns, &offset)) return true;
  return offset > kMaxClockOffsetNs || offset < -kMaxClockOffsetNs;
}

std::string OffClockDetail(int64_t time_ns, int64_t now_ns) {
  return std::to_string((static_cast<double>(now_ns) - static_cast<double>(time_ns)) * 1e-9) +
         " s before its arrival, on another clock than the host's (a recording replayed without "
         "--restamp?)";
}

}  // namespace

InputPath::InputPath(const Rig& rig, const std::vector<ImuSite>& imus, const KeypointLayout& layout,
                     const SyncOptions& sync, double min_confidence, bool everyone)
    : rig_(rig),
      everyone_(everyone),
      decoder_(rig, imus, layout),
      selector_(static_cast<int>(rig.cameras.size()), min_confidence),
      sync_(static_cast<int>(rig.cameras.size()), static_cast<int>(imus.size()), sync),
      monitor_(Names(rig.cameras), Names(imus)),
      camera_link_(rig.cameras.size(), kNoLink),
      imu_link_(imus.size(), kNoLink) {}

void InputPath::LinkDown(int link) {
  if (link == kNoLink) return;
  std::vector<int> cameras, imus;
  for (size_t c = 0; c < camera_link_.size(); ++c)
    if (camera_link_[c] == link) cameras.push_back(static_cast<int>(c));
  for (size_t i = 0; i < imu_link_.size(); ++i)
    if (imu_link_[i] == link) imus.push_back(static_cast<int>(i));
  sync_.MarkLinkDown(cameras, imus);
}

bool InputPath::Feed(std::string_view type, std::string_view payload, int64_t now_ns,
                     const Solver* tracker, std::string* why, int link) {
  const wire::Decoded d = wire::DecodeMessage(type, payload);
  if (!d.message) return monitor_.Drop(wire::ToString(d.reason), d.detail, why);
  return Feed(*d.message, now_ns, tracker, why, link);
}

bool InputPath::Feed(const google::protobuf::Message& message, int64_t now_ns,
                     const Solver* tracker, std::string* why, int link) {
  if (auto* frame = dynamic_cast<const v1::KeypointFrame*>(&message))
    return FeedKeypoints(*frame, now_ns, tracker, why, link);
  if (auto* batch = dynamic_cast<const v1::ImuBatch*>(&message))
    return FeedImus(*batch, now_ns, why, link);
  return monitor_.Drop("not_an_input", wire::TypeName(message) + " is not an input of the host",
                       why);
}

bool InputPath::FeedKeypoints(const v1::KeypointFrame& frame, int64_t now_ns, const Solver* tracker,
                              std::string* why, int link) {
  int c = -1;
  Rejection rejection;
  if (!decoder_.CameraOf(frame, &c, &rejection)) {
    if (c >= 0) monitor_.camera(c).invalid++;
    return monitor_.Drop(rejection.reason, rejection.detail, why);
  }
  camera_link_[c] = link;
  StreamStats& stats = monitor_.camera(c);
  stats.Count(frame.frame_index(), 0, frame.capture_time_ns(), now_ns);
  if (OffClock(frame.capture_time_ns(), now_ns)) {
    return monitor_.Drop("clock_offset",
                         frame.camera_id() + " frame " + std::to_string(frame.frame_index()) +
                             " captured " + OffClockDetail(frame.capture_time_ns(), now_ns),
                         why);
  }
  if (!stats.clock.Check(frame.capture_time_ns(), now_ns)) {
    const int64_t ms = (now_ns - frame.capture_time_ns()) / 1'000'000;
    return monitor_.Drop("clock_step",
                         frame.camera_id() + " frame " + std::to_string(frame.frame_index()) +
                             " arrived " + std::to_string(ms < 0 ? -ms : ms) + " ms " +
                             (ms < 0 ? "before" : "after") + " its time: its clock is off",
                         why);
  }
  if (everyone_) {  // a session of several people: they are told apart after synchronisation
    if (!sync_.AddCamera(decoder_.ToCameraInputEveryone(frame, c), now_ns))
      return monitor_.Drop("late_or_duplicate",
                           frame.camera_id() + " frame " + std::to_string(frame.frame_index()),
                           why);
    return true;
  }
  // Projecting the tracked pose is needed only to tell several persons apart.
  const bool track =
      tracker && tracker->initialised() && frame.detected() && frame.persons_size() > 1;
  const std::vector<Eigen::Vector2d> predicted =
      track ? ProjectSites(*tracker, rig_.cameras[c]) : std::vector<Eigen::Vector2d>();
  const int subject = selector_.Choose(frame, c, track ? &predicted : nullptr);
  if (!sync_.AddCamera(decoder_.ToCameraInput(frame, c, subject), now_ns)) {
    return monitor_.Drop("late_or_duplicate",
                         frame.camera_id() + " frame " + std::to_string(frame.frame_index()), why);
  }
  return true;
}

bool InputPath::FeedImus(const v1::ImuBatch& batch, int64_t now_ns, std::string* why, int link) {
  monitor_.hub(batch.hub_id()).Count(batch.sequence(), 0, batch.send_time_ns(), now_ns);
  int unknown = 0, off_clock = 0;
  int64_t off_time_ns = 0;
  for (const v1::ImuSample& s : batch.samples()) {
    const int i = decoder_.ImuOf(s.sensor_id());
    if (i < 0) {
      unknown++;
      continue;
    }
    imu_link_[i] = link;
    monitor_.imu(i).Count(s.packet_counter(), 1u << 16, s.sample_time_ns(), now_ns);
    if (OffClock(s.sample_time_ns(), now_ns)) {
      off_clock++;
      off_time_ns = s.sample_time_ns();
      continue;
    }
    if (!monitor_.imu(i).clock.Check(s.sample_time_ns(), now_ns)) {
      monitor_.CountDropped("clock_step");
      continue;
    }
    if (!sync_.AddImu(InputDecoder::ToImuInput(s, i), now_ns))
      monitor_.CountDropped("late_or_duplicate");
  }
  if (off_clock > 0) {
    monitor_.CountDropped("clock_offset", off_clock - 1);
    monitor_.Drop("clock_offset",
                  std::to_string(off_clock) + " samples of hub " + batch.hub_id() + ", sampled " +
                      OffClockDetail(off_time_ns, now_ns),
                  unknown == 0 ? why : nullptr);
    if (unknown == 0) return false;
  }
  if (unknown == 0) return true;
  monitor_.CountDropped("unknown_source", unknown - 1);
  return monitor_.Drop("unknown_source",
                       std::to_string(unknown) + " samples of sensors not in the IMU set (hub " +
                           batch.hub_id() + ")",
                       why);
}

}  // namespace mocap
