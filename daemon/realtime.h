// Real-time scheduling for the control loop's thread and the API thread (sched(7)).
//
// The loop runs SCHED_FIFO at [control].realtime_priority so that a busy host
// (builds, an API flood, a map being written) cannot delay a period; the API
// thread runs one priority below it. The API thread must be real time too: the
// two hand work to each other through Boost.Asio's scheduler queues, whose
// mutexes do not inherit priority, so an API thread preempted by an ordinary
// process while it holds one stalls the loop (measured: jitter p99 5.1 ms with
// the loop alone real time, 1.1 ms with both; docs/reliability.md). The API
// thread's CPU is bounded by its share (api.cpu_share of each window), so it
// cannot starve the host. Threads that do file I/O (the map writer, the bus
// recorder) keep normal scheduling: SCHED_RESET_ON_FORK makes every thread
// started by a real-time thread, and any child, start under SCHED_OTHER.
//
// Permission: CAP_SYS_NICE, or RLIMIT_RTPRIO >= the priority (the shipped unit
// sets LimitRTPRIO= and lets sched_setscheduler(2) through its system-call
// filter; docs/systemd.md). Refused, the threads keep normal scheduling and
// the daemon says why in the log and in status.period.scheduling: it never
// fails the start.
#ifndef IRSLAM_DAEMON_REALTIME_H_
#define IRSLAM_DAEMON_REALTIME_H_

#include <pthread.h>

#include <string>

namespace irslam {

// A thread's scheduling after SetThreadScheduling.
struct ThreadScheduling {
  bool realtime = false;  // SCHED_FIFO in effect
  int priority = 0;       // its priority (0: normal scheduling)
  std::string error;      // why the requested priority was refused ("" if it was not)
  // "fifo 10", "normal", or "normal (SCHED_FIFO 10 refused: Operation not permitted)".
  std::string Describe(int requested) const;
};

// priority 1..99: SCHED_FIFO | SCHED_RESET_ON_FORK for the thread; 0: back to
// SCHED_OTHER, only if the thread is real time now (so a daemon configured
// without real time never makes the system call a unit may filter).
ThreadScheduling SetThreadScheduling(pthread_t thread, int priority);

// The API thread's priority for a loop priority: one below it (0: normal).
inline int ApiThreadPriority(int loop_priority) { return loop_priority > 1 ? loop_priority - 1 : 0; }

// The calling thread's (the control loop calls it for itself).
inline ThreadScheduling SetLoopScheduling(int priority) { return SetThreadScheduling(pthread_self(), priority); }

}  // namespace irslam

#endif  // IRSLAM_DAEMON_REALTIME_H_
