#include "daemon/realtime.h"

#include <sched.h>

#include <cstring>

namespace irslam {
namespace {

// The thread's present scheduling (errors read as normal scheduling).
ThreadScheduling Current(pthread_t thread) {
  ThreadScheduling s;
  int policy = SCHED_OTHER;
  sched_param p{};
  if (::pthread_getschedparam(thread, &policy, &p) == 0 && (policy & ~SCHED_RESET_ON_FORK) == SCHED_FIFO) {
    s.realtime = true;
    s.priority = p.sched_priority;
  }
  return s;
}

}  // namespace

std::string ThreadScheduling::Describe(int requested) const {
  if (realtime) return "fifo " + std::to_string(priority);
  if (error.empty()) return "normal";
  return "normal (SCHED_FIFO " + std::to_string(requested) + " refused: " + error + ")";
}

ThreadScheduling SetThreadScheduling(pthread_t thread, int priority) {
  const ThreadScheduling now = Current(thread);
  if (priority <= 0 && !now.realtime) return now;
  sched_param p{};
  p.sched_priority = priority > 0 ? priority : 0;
  const int policy = priority > 0 ? (SCHED_FIFO | SCHED_RESET_ON_FORK) : SCHED_OTHER;
  if (const int err = ::pthread_setschedparam(thread, policy, &p); err != 0) {
    ThreadScheduling kept = now;  // unchanged
    kept.error = std::strerror(err);
    return kept;
  }
  ThreadScheduling s;
  s.realtime = priority > 0;
  s.priority = s.realtime ? priority : 0;
  return s;
}

}  // namespace irslam
