#include "daemon/jsonrpc.h"

#include <algorithm>

#include "io/json_text.h"

namespace irslam::rpc {

nlohmann::json MakeResult(const nlohmann::json& id, nlohmann::json result) {
  return {{"jsonrpc", "2.0"}, {"id", id}, {"result", std::move(result)}};
}

nlohmann::json MakeError(const nlohmann::json& id, int code, const std::string& message) {
  return {{"jsonrpc", "2.0"}, {"id", id}, {"error", {{"code", code}, {"message", message}}}};
}

nlohmann::json MakeNotification(const std::string& method, nlohmann::json params) {
  return {{"jsonrpc", "2.0"}, {"method", method}, {"params", std::move(params)}};
}

std::string MessageText(const nlohmann::json& message) { return DumpJson(message); }

std::string ResultText(const nlohmann::json& id, const std::string& result_text) {
  // The keys in the order nlohmann's object (sorted) gives them: id, jsonrpc, result.
  std::string text = "{\"id\":";
  text += DumpJson(id);
  text += ",\"jsonrpc\":\"2.0\",\"result\":";
  text += result_text;
  text += '}';
  return text;
}

std::string EscapeForLog(std::string_view text, size_t max_bytes) {
  std::string out;
  const size_t n = std::min(text.size(), max_bytes);
  out.reserve(n + 8);
  for (size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 || c >= 0x7f || c == '\\') {
      static constexpr char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
    } else {
      out += static_cast<char>(c);
    }
  }
  if (text.size() > max_bytes) out += "...";
  return out;
}

ParseResult ParseRequest(std::string_view line) {
  std::string error;
  const std::optional<nlohmann::json> j = ParseJsonText(line, &error);
  if (!j) return MakeError(nullptr, kParseError, "parse error: " + error);
  if (!j->is_object()) {
    return MakeError(nullptr, kInvalidRequest,
                     j->is_array() ? "invalid request: batches are not supported"
                                   : "invalid request: not an object");
  }
  nlohmann::json id = nullptr;
  bool has_id = false;
  if (auto it = j->find("id"); it != j->end()) {
    if (!it->is_null() && !it->is_string() && !it->is_number_integer()) {
      return MakeError(nullptr, kInvalidRequest, "invalid request: id must be a string or integer");
    }
    id = *it;
    has_id = true;
  }
  auto ver = j->find("jsonrpc");
  if (ver == j->end() || *ver != "2.0") {
    return MakeError(id, kInvalidRequest, "invalid request: jsonrpc must be \"2.0\"");
  }
  auto method = j->find("method");
  if (method == j->end() || !method->is_string()) {
    return MakeError(id, kInvalidRequest, "invalid request: method must be a string");
  }
  Request r;
  r.id = id;
  r.notification = !has_id;
  r.method = method->get<std::string>();
  if (auto p = j->find("params"); p != j->end()) {
    if (!p->is_object() && !p->is_array()) {
      return MakeError(id, kInvalidParams, "invalid params: must be an object");
    }
    if (p->is_array() && !p->empty()) {
      return MakeError(id, kInvalidParams, "invalid params: use named parameters");
    }
    r.params = p->is_object() ? *p : nlohmann::json::object();
  }
  return r;
}

}  // namespace irslam::rpc
