// Blocking JSON-RPC client (every wait has a timeout) for the control API (irslamctl and the tests).
#ifndef IRSLAM_DAEMON_RPC_CLIENT_H_
#define IRSLAM_DAEMON_RPC_CLIENT_H_

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace irslam {

class RpcClient {
 public:
  RpcClient() = default;
  ~RpcClient();
  RpcClient(const RpcClient&) = delete;
  RpcClient& operator=(const RpcClient&) = delete;

  // Gives up after timeout_s (a hung daemon whose backlog is full).
  bool Connect(const std::string& path, std::string* error, double timeout_s = 5);
  // Sends a request and waits for its response (skipping notifications).
  // Returns the result; on a JSON-RPC error or I/O problem returns nullopt and
  // sets *error (one line).
  std::optional<nlohmann::json> Call(const std::string& method, const nlohmann::json& params,
                                     double timeout_s, std::string* error);
  // Waits for the next notification's params (e.g. a status update).
  std::optional<nlohmann::json> NextNotification(double timeout_s, std::string* error);
  // Raw access for tests: send text as is / read one line.
  bool SendRaw(const std::string& text, std::string* error);
  std::optional<std::string> ReadLine(double timeout_s, std::string* error);
  void Close();

 private:
  static constexpr double kSendTimeoutS = 10;
  int fd_ = -1;
  int next_id_ = 1;
  std::string buffer_;
};

// The socket path irslamctl uses: --socket, else $IRSLAM_SOCKET, else the default.
std::string DefaultSocketPath();

}  // namespace irslam

#endif  // IRSLAM_DAEMON_RPC_CLIENT_H_
