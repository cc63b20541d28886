// The control loop's real-time scheduling (daemon/realtime.h). Each test runs
// in a forked child, so the test runner's own thread is never made real time.
#include <gtest/gtest.h>
#include <linux/filter.h>
#include <linux/seccomp.h>
#include <sched.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstring>
#include <atomic>
#include <functional>
#include <thread>

#include "daemon/realtime.h"

namespace irslam {
namespace {

// Runs body in a child process; its return value is the child's exit status.
int InChild(const std::function<int()>& body) {
  const pid_t pid = ::fork();
  if (pid == 0) ::_exit(body());
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 100 + WTERMSIG(status);
}

int Policy() { return ::sched_getscheduler(0) & ~SCHED_RESET_ON_FORK; }

TEST(RealtimeTest, TheCallingThreadAndOneOtherRunRealTimeAndThreadsStartedAfterDoNot) {
  const int r = InChild([] {
    rlimit lim{10, 10};
    ::setrlimit(RLIMIT_RTPRIO, &lim);  // what the unit's LimitRTPRIO=10 gives
    const ThreadScheduling s = SetLoopScheduling(10);
    if (!s.realtime) return 77;  // this host refuses real time even so (a container)
    if (s.priority != 10 || !s.error.empty() || s.Describe(10) != "fifo 10") return 1;
    if (Policy() != SCHED_FIFO) return 2;
    if ((::sched_getscheduler(0) & SCHED_RESET_ON_FORK) == 0) return 3;
    int worker = -1;
    std::thread([&] { worker = Policy(); }).join();
    if (worker != SCHED_OTHER) return 4;  // the writer threads: normal
    // Another thread (the API thread) made real time one priority below.
    std::atomic<int> stage{0};
    int api_policy = -1, api_priority = -1;
    std::thread api([&] {
      while (stage.load() == 0) std::this_thread::yield();
      sched_param p{};
      ::pthread_getschedparam(pthread_self(), &api_policy, &p);
      api_priority = p.sched_priority;
    });
    const ThreadScheduling a = SetThreadScheduling(api.native_handle(), 9);
    stage = 1;
    api.join();
    if (!a.realtime || a.Describe(9) != "fifo 9") return 7;
    if ((api_policy & ~SCHED_RESET_ON_FORK) != SCHED_FIFO || api_priority != 9) return 8;
    const ThreadScheduling back = SetLoopScheduling(0);  // a reload to 0
    if (back.realtime || !back.error.empty() || back.Describe(0) != "normal") return 5;
    if (Policy() != SCHED_OTHER) return 6;
    return 0;
  });
  if (r == 77) GTEST_SKIP() << "SCHED_FIFO refused here even with RLIMIT_RTPRIO 10";
  EXPECT_EQ(r, 0);
}

TEST(RealtimeTest, ARefusedPriorityKeepsNormalSchedulingAndSaysWhy) {
  const int r = InChild([] {
    if (::geteuid() == 0 && (::setgid(65534) != 0 || ::setuid(65534) != 0)) return 10;  // no CAP_SYS_NICE
    rlimit lim{0, 0};
    if (::setrlimit(RLIMIT_RTPRIO, &lim) != 0) return 11;
    const ThreadScheduling s = SetLoopScheduling(10);
    if (s.realtime || s.priority != 0) return 1;
    if (s.error != std::strerror(EPERM)) return 2;
    if (s.Describe(10) != std::string("normal (SCHED_FIFO 10 refused: ") + std::strerror(EPERM) + ")") return 3;
    if (Policy() != SCHED_OTHER) return 4;
    return 0;
  });
  EXPECT_EQ(r, 0);
}

// A seccomp filter like a unit's SystemCallFilter=~@resources: sched_setscheduler
// fails with EACCES (a unit would kill the process instead).
bool DenySchedSetscheduler() {
  sock_filter code[] = {
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(seccomp_data, nr)),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, __NR_sched_setscheduler, 0, 1),
      BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ERRNO | EACCES),
      BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ALLOW),
  };
  sock_fprog prog{static_cast<unsigned short>(sizeof code / sizeof code[0]), code};
  return ::prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) == 0 && ::prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, &prog) == 0;
}

TEST(RealtimeTest, ZeroNeverCallsTheSchedulerWhenTheThreadIsNotRealTime) {
  // realtime_priority = 0 under a unit whose filter denies sched_setscheduler
  // must not make the call (it would be killed).
  const int r = InChild([] {
    if (!DenySchedSetscheduler()) return 10;
    const ThreadScheduling s = SetLoopScheduling(0);
    if (s.realtime || !s.error.empty() || s.Describe(0) != "normal") return 1;
    // The filter works: asking for real time is refused by it.
    const ThreadScheduling rt = SetLoopScheduling(10);
    return !rt.realtime && rt.error == std::strerror(EACCES) ? 0 : 2;
  });
  EXPECT_EQ(r, 0);
}

}  // namespace
}  // namespace irslam
