#include "tests/testing/process.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <thread>

namespace irslam::testing {

Process::~Process() {
  if (running()) {
    Signal(SIGKILL);
    Wait(5);
  }
}

bool Process::Start(const std::vector<std::string>& argv, const std::string& log_path,
                    const std::vector<std::string>& extra_env) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_ = ::fork();
  if (pid_ < 0) return false;
  if (pid_ == 0) {
    const int fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd >= 0) {
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      ::close(fd);
    }
    for (const auto& kv : extra_env) ::putenv(const_cast<char*>(kv.c_str()));
    ::execv(args[0], args.data());
    _exit(127);
  }
  status_.reset();
  return true;
}

bool Process::Signal(int signo) { return pid_ > 0 && ::kill(pid_, signo) == 0; }

bool Process::running() {
  if (pid_ <= 0 || status_) return false;
  int st;
  const pid_t r = ::waitpid(pid_, &st, WNOHANG);
  if (r == pid_) {
    status_ = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    return false;
  }
  return true;
}

std::optional<int> Process::Wait(double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::milliseconds(static_cast<int>(timeout_s * 1000));
  while (running()) {
    if (std::chrono::steady_clock::now() > deadline) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return status_;
}

int RunCommand(const std::vector<std::string>& argv, std::string* output, double timeout_s) {
  const std::string log = MakeTempDir() + "/out.txt";
  Process p;
  if (!p.Start(argv, log)) return -1;
  auto st = p.Wait(timeout_s);
  if (!st) {
    p.Signal(SIGKILL);
    st = p.Wait(5);
  }
  if (output) *output = ReadFile(log);
  return st.value_or(-1);
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string MakeTempDir() {
  char tmpl[] = "/tmp/irslam-test.XXXXXX";
  const char* d = ::mkdtemp(tmpl);
  return d ? d : "/tmp";
}

}  // namespace irslam::testing
