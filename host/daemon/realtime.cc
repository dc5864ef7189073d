#include "realtime.h"

#include <sched.h>

#include <cerrno>
#include <cstring>

namespace mocap {

bool EnterRealtime(int priority, std::string* why) {
  sched_param param{};
  param.sched_priority = priority;
  if (sched_setscheduler(0, SCHED_FIFO, &param) != 0) {
    const int e = errno;
    *why =
        std::string("SCHED_FIFO refused: ") + std::strerror(e) +
        (e == EPERM ? " (needs CAP_SYS_NICE, or RLIMIT_RTPRIO / LimitRTPRIO= in the service unit)"
                    : "");
    return false;
  }
  return true;
}

}  // namespace mocap
