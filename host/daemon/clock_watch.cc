#include "clock_watch.h"

#include <cstdlib>

namespace mocap {

bool ClockWatch::Check(int64_t time_ns, int64_t now_ns) {
  const int64_t offset = now_ns - time_ns;
  if (!settled_) {
    if (offset >= -kStepNs) settled_ = offset;  // the first message on a plausible clock
    dropped_ += !settled_;
    return settled_.has_value();
  }
  if (std::llabs(offset - *settled_) <= kStepNs) {
    if (off_since_ns_) steps_++;  // back on the settled clock
    off_since_ns_.reset();
    suspect_.reset();
    *settled_ += (offset - *settled_) / 16;  // follows slow drift and the latency's level
    return true;
  }
  if (offset < *settled_ - kStepNs && offset >= -kStepNs) {
    // Sooner after its time than the settled offset says, and not from the future: the offset
    // had settled on a backlog's (a box that sent what it had queued at once), not a step.
    settled_ = offset;
    suspect_.reset();
    off_since_ns_.reset();
    return true;
  }
  if (!suspect_ || std::llabs(offset - *suspect_) > kStepNs) {  // a new level
    suspect_ = offset;
    suspect_since_ns_ = now_ns;
    suspect_counted_ = false;
  }
  if (!suspect_counted_ && now_ns - suspect_since_ns_ >= kConfirmNs) {
    steps_++;  // from the settled clock, or from one off level to another
    suspect_counted_ = true;
    if (!off_since_ns_) off_since_ns_ = now_ns;
  }
  if (off_since_ns_ && now_ns - *off_since_ns_ >= kRelearnNs) {
    settled_ = offset;  // off for so long: the sender's clock is the clock now
    off_since_ns_.reset();
    suspect_.reset();
    return true;
  }
  // A delayed message (behind the settled offset) is left to the synchroniser, which takes it
  // or counts it late, until a step is confirmed; one from the future never is.
  const bool take = !off_since_ns_ && offset > *settled_;
  dropped_ += !take;
  return take;
}

}  // namespace mocap
