// libFuzzer target: one line of the control API (daemon/jsonrpc.h) and the
// answer built for it. Any crash, sanitizer report or exception escaping is a bug.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "daemon/jsonrpc.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view line(reinterpret_cast<const char*>(data), size);
  const auto parsed = irslam::rpc::ParseRequest(line);
  if (const auto* req = std::get_if<irslam::rpc::Request>(&parsed)) {
    // What the server sends back must always serialise (ids of any JSON type).
    (void)irslam::rpc::MakeResult(req->id, req->params).dump();
    (void)irslam::rpc::MakeError(req->id, irslam::rpc::kMethodNotFound, "method not found: " + req->method)
        .dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  } else {
    (void)std::get<nlohmann::json>(parsed).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  }
  return 0;
}
