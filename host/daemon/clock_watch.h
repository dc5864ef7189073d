// A stream's clock against the host's: a step of the sender's clock (a PTP loss, a clock set
// by hand) moves every message's offset (arrival on the host's clock - the sender's time) at
// once and keeps it there, where a stall of the network or of the host delays a backlog that
// then drains. A message whose offset leaves the stream's settled offset by more than kStepNs
// is out of band; out-of-band messages at one offset for kConfirmNs of arrival time are a step
// (counted, as is a move from one such offset to another), and the stream is off its clock
// until its offsets return to the settled one (the clock locked again: counted too). Its
// messages are refused while it is off, and any that would come from the future (ahead of the
// settled offset by kStepNs and of the host's clock), so a box's frames are never fused with
// frames of another time; a stream off for kRelearnNs takes its new offset as settled (a step
// of the host's own clock otherwise left every stream out for good). An offset that settled on
// a backlog (a box that sent its queue at once) gives way to the first message that arrives
// sooner without being from the future.
#ifndef MOCAP_DAEMON_CLOCK_WATCH_H_
#define MOCAP_DAEMON_CLOCK_WATCH_H_

#include <cstdint>
#include <optional>

namespace mocap {

class ClockWatch {
 public:
  static constexpr int64_t kStepNs = 250'000'000;
  static constexpr int64_t kConfirmNs = 100'000'000;
  static constexpr int64_t kRelearnNs = 10'000'000'000;

  // Whether the message with the sender's time time_ns, received at now_ns, is on the
  // stream's clock (false: refuse it; counted in dropped()).
  bool Check(int64_t time_ns, int64_t now_ns);

  uint64_t steps() const { return steps_; }      // steps seen, and returns to the settled clock
  uint64_t dropped() const { return dropped_; }  // messages refused
  bool off() const { return off_since_ns_.has_value(); }

 private:
  std::optional<int64_t> settled_;  // offset while on the clock (tracked slowly)
  std::optional<int64_t> suspect_;  // offset of the out-of-band messages in a row
  int64_t suspect_since_ns_ = 0;
  bool suspect_counted_ =
      false;  // its level was counted as a step         // arrival of the first of them
  std::optional<int64_t> off_since_ns_;  // the step's confirmation
  uint64_t steps_ = 0, dropped_ = 0;
};

}  // namespace mocap

#endif  // MOCAP_DAEMON_CLOCK_WATCH_H_
