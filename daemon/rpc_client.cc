#include "daemon/rpc_client.h"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "io/json_text.h"

namespace irslam {

std::string DefaultSocketPath() {
  const char* env = std::getenv("IRSLAM_SOCKET");
  if (env != nullptr && *env != '\0') return env;
  return "/run/irslam/irslamd.sock";
}

RpcClient::~RpcClient() { Close(); }

void RpcClient::Close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  buffer_.clear();
}

namespace {
using Clock = std::chrono::steady_clock;

Clock::time_point Deadline(double timeout_s) {
  return Clock::now() +
         std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
}

int MsLeft(Clock::time_point deadline) {
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
  return ms <= 0 ? 0 : static_cast<int>(std::min<int64_t>(ms, 1 << 30));
}
}  // namespace

bool RpcClient::Connect(const std::string& path, std::string* error, double timeout_s) {
  Close();
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (path.size() >= sizeof(addr.sun_path)) {
    *error = "socket path too long: " + path;
    return false;
  }
  std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
  const auto fail = [&](const std::string& why) {
    *error = "cannot reach irslamd at " + path + ": " + why;
    Close();
    return false;
  };
  // Non-blocking: a hung daemon whose backlog is full must not hang the caller.
  fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (fd_ < 0) return fail(std::strerror(errno));
  const auto deadline = Deadline(timeout_s);
  for (;;) {
    if (::connect(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0) return true;
    const int err = errno;
    if (err == EINTR) continue;
    if (err == EAGAIN) {  // a Unix socket's backlog is full: try again until the deadline
      if (MsLeft(deadline) == 0) {
        char msg[96];
        std::snprintf(msg, sizeof msg, "timed out after %g s (its backlog is full)", timeout_s);
        return fail(msg);
      }
      ::poll(nullptr, 0, std::min(10, MsLeft(deadline)));
      continue;
    }
    if (err != EINPROGRESS) return fail(std::strerror(err));
    pollfd p{fd_, POLLOUT, 0};
    const int r = ::poll(&p, 1, MsLeft(deadline));
    if (r < 0 && errno == EINTR) continue;
    if (r == 0) {
      char msg[64];
      std::snprintf(msg, sizeof msg, "timed out after %g s", timeout_s);
      return fail(msg);
    }
    int so_error = 0;
    socklen_t len = sizeof so_error;
    ::getsockopt(fd_, SOL_SOCKET, SO_ERROR, &so_error, &len);
    if (so_error != 0) return fail(std::strerror(so_error));
    return true;
  }
}

bool RpcClient::SendRaw(const std::string& text, std::string* error) {
  size_t off = 0;
  const auto deadline = Deadline(kSendTimeoutS);
  while (off < text.size()) {
    const ssize_t n = ::send(fd_, text.data() + off, text.size() - off, MSG_NOSIGNAL);
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno == EAGAIN) {  // the daemon reads slowly: wait, but not for ever
        pollfd p{fd_, POLLOUT, 0};
        if (MsLeft(deadline) == 0 || ::poll(&p, 1, MsLeft(deadline)) == 0) {
          *error = "send: timed out: irslamd does not read";
          return false;
        }
        continue;
      }
      *error = std::string("send: ") + std::strerror(errno);
      return false;
    }
    off += static_cast<size_t>(n);
  }
  return true;
}

std::optional<std::string> RpcClient::ReadLine(double timeout_s, std::string* error) {
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(timeout_s));
  for (;;) {
    const auto nl = buffer_.find('\n');
    if (nl != std::string::npos) {
      std::string line = buffer_.substr(0, nl);
      buffer_.erase(0, nl + 1);
      return line;
    }
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) {
      *error = "timed out waiting for irslamd";
      return std::nullopt;
    }
    pollfd p{fd_, POLLIN, 0};
    const int r = ::poll(&p, 1, static_cast<int>(left));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) continue;
    char buf[65536];
    const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
    if (n == 0) {
      *error = "irslamd closed the connection";
      return std::nullopt;
    }
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      *error = std::string("recv: ") + std::strerror(errno);
      return std::nullopt;
    }
    buffer_.append(buf, static_cast<size_t>(n));
  }
}

std::optional<nlohmann::json> RpcClient::Call(const std::string& method,
                                              const nlohmann::json& params, double timeout_s,
                                              std::string* error) {
  if (fd_ < 0) {
    *error = "not connected";
    return std::nullopt;
  }
  const int id = next_id_++;
  const nlohmann::json req = {{"jsonrpc", "2.0"}, {"id", id}, {"method", method}, {"params", params}};
  if (!SendRaw(req.dump() + "\n", error)) return std::nullopt;
  for (;;) {
    auto line = ReadLine(timeout_s, error);
    if (!line) return std::nullopt;
    auto j = ParseJsonText(*line, error);
    if (!j || !j->is_object()) {
      *error = "irslamd sent something that is not a JSON object";
      return std::nullopt;
    }
    if (!j->contains("id") || (*j)["id"] != id) continue;  // a notification
    if (j->contains("error")) {
      *error = (*j)["error"].value("message", std::string("error"));
      return std::nullopt;
    }
    return (*j)["result"];
  }
}

std::optional<nlohmann::json> RpcClient::NextNotification(double timeout_s, std::string* error) {
  for (;;) {
    auto line = ReadLine(timeout_s, error);
    if (!line) return std::nullopt;
    auto j = ParseJsonText(*line, error);
    if (!j || !j->is_object()) continue;
    if (j->contains("method") && !j->contains("id")) return (*j)["params"];
  }
}

}  // namespace irslam
