// Real-time scheduling for the solving process: SCHED_FIFO, as audio servers and robot
// controllers run. A frame's solve is a millisecond or two of CPU that must not wait behind
// ordinary processes sharing the host (an edge process, the live calibrator, a viewer).
#ifndef MOCAP_DAEMON_REALTIME_H_
#define MOCAP_DAEMON_REALTIME_H_

#include <string>

namespace mocap {

constexpr int kMinRealtimePriority = 1, kMaxRealtimePriority = 99;

// Puts the calling thread (and every thread it starts afterwards: call it before the
// ZeroMQ context) under SCHED_FIFO at `priority` (1-99). False with *why when the kernel
// refuses: no CAP_SYS_NICE and no RLIMIT_RTPRIO allowance, or a priority outside 1-99.
bool EnterRealtime(int priority, std::string* why);

}  // namespace mocap

#endif  // MOCAP_DAEMON_REALTIME_H_
