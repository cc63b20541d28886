// Test helpers: run the real binaries as child processes.
#ifndef IRSLAM_TESTS_TESTING_PROCESS_H_
#define IRSLAM_TESTS_TESTING_PROCESS_H_

#include <sys/types.h>

#include <optional>
#include <string>
#include <vector>

namespace irslam::testing {

// irslam-sim serve's --realtime-priority in the test rigs: SCHED_FIFO above the
// daemon's loop (10). The simulator stands for the motor controller, its own
// microcontroller, which a loaded host never delays; starved under ctest -j2
// with sanitizers, it simulated the missed robot time in bursts under a stale
// wheel command (a cleaning run in CI hit a wall so). Refused (not root), the
// simulator says so and runs normally.
inline constexpr const char* kSimRealtimePriority = "20";

class Process {
 public:
  Process() = default;
  ~Process();
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  // Starts argv[0] with arguments; stdout and stderr go to log_path (appended).
  bool Start(const std::vector<std::string>& argv, const std::string& log_path,
             const std::vector<std::string>& extra_env = {});
  bool Signal(int signo);
  // Waits up to timeout_s; returns the exit status (128+signal if killed by one).
  std::optional<int> Wait(double timeout_s);
  bool running();
  pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  std::optional<int> status_;
};

// Runs a command to completion, capturing stdout+stderr; returns its exit status.
int RunCommand(const std::vector<std::string>& argv, std::string* output, double timeout_s = 30);

std::string ReadFile(const std::string& path);
// A fresh temporary directory (removed by the caller if wanted).
std::string MakeTempDir();

}  // namespace irslam::testing

#endif  // IRSLAM_TESTS_TESTING_PROCESS_H_
