#include "daemon/rpc_client.h"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
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

bool RpcClient::Connect(const std::string& path, std::string* error) {
  Close();
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (path.size() >= sizeof(addr.sun_path)) {
    *error = "socket path too long: " + path;
    return false;
  }
  std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
  fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0 || ::connect(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    *error = "cannot reach irslamd at " + path + ": " + std::strerror(errno);
    Close();
    return false;
  }
  return true;
}

bool RpcClient::SendRaw(const std::string& text, std::string* error) {
  size_t off = 0;
  while (off < text.size()) {
    const ssize_t n = ::send(fd_, text.data() + off, text.size() - off, MSG_NOSIGNAL);
    if (n < 0) {
      if (errno == EINTR) continue;
      *error = std::string("send: ") + std::strerror(errno);
      return false;
    }
    off += static_cast<size_t>(n);
  }
  return true;
}

std::optional<std::string> RpcClient::ReadLine(double timeout_s, std::string* error) {
  using Clock = std::chrono::steady_clock;
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
      if (errno == EINTR) continue;
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
