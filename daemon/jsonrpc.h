// JSON-RPC 2.0 framing for the control API (contracts.md §6): one JSON object per
// line. Pure functions: text in, request or ready-made error response out.
#ifndef IRSLAM_DAEMON_JSONRPC_H_
#define IRSLAM_DAEMON_JSONRPC_H_

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <variant>

namespace irslam::rpc {

inline constexpr int kParseError = -32700;
inline constexpr int kInvalidRequest = -32600;
inline constexpr int kMethodNotFound = -32601;
inline constexpr int kInvalidParams = -32602;
inline constexpr int kInternalError = -32603;
// Application errors (server-defined range).
inline constexpr int kRejected = -32000;     // command not possible in this state
inline constexpr int kAccessDenied = -32001;

struct Request {
  nlohmann::json id;  // null for notifications
  bool notification = false;
  std::string method;
  nlohmann::json params = nlohmann::json::object();
};

// Either a request or the error response to send back.
using ParseResult = std::variant<Request, nlohmann::json>;
ParseResult ParseRequest(std::string_view line);

nlohmann::json MakeResult(const nlohmann::json& id, nlohmann::json result);
nlohmann::json MakeError(const nlohmann::json& id, int code, const std::string& message);
nlohmann::json MakeNotification(const std::string& method, nlohmann::json params);

// The text the server sends for a message (response or notification), without
// the newline. Never throws: invalid UTF-8 a client sent (echoed in an id or a
// method name) is replaced with U+FFFD (io/json_text.h DumpJson).
std::string MessageText(const nlohmann::json& message);
// MessageText(MakeResult(id, result)) for a result already serialised as
// result_text (one serialisation of `status` or `map` shared by many replies).
std::string ResultText(const nlohmann::json& id, const std::string& result_text);

// A client-supplied string made safe for one log line: control characters,
// backslashes and bytes >= 0x7f as \xNN, at most max_bytes of input (then "...").
std::string EscapeForLog(std::string_view text, size_t max_bytes = 64);

}  // namespace irslam::rpc

#endif  // IRSLAM_DAEMON_JSONRPC_H_
