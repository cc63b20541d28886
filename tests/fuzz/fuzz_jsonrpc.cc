// libFuzzer target: one line of the control API (daemon/jsonrpc.h) and the
// answer built for it, serialised exactly as the server serialises it
// (rpc::MessageText / rpc::ResultText). Any crash, sanitizer report or
// exception escaping is a bug, and so is a reply that is not valid JSON.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "daemon/jsonrpc.h"

namespace {
void CheckValid(const std::string& text) {
  // What goes out must be valid JSON (UTF-8 included), one line.
  if (text.find('\n') != std::string::npos ||
      !nlohmann::json::accept(text.begin(), text.end())) {
    std::abort();
  }
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace irslam::rpc;
  const std::string_view line(reinterpret_cast<const char*>(data), size);
  const auto parsed = ParseRequest(line);
  if (const auto* req = std::get_if<Request>(&parsed)) {
    // Ids of any JSON type, method names and params as the client sent them.
    CheckValid(MessageText(MakeError(req->id, kMethodNotFound, "method not found: " + req->method)));
    CheckValid(MessageText(MakeResult(req->id, req->params)));
    CheckValid(ResultText(req->id, MessageText(req->params)));
    (void)EscapeForLog(req->method);
  } else {
    CheckValid(MessageText(std::get<nlohmann::json>(parsed)));
  }
  return 0;
}
