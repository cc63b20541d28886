// libFuzzer target: irslamd config files (JSON with comments, daemon/config.h).
// A rejected config must leave the options exactly as they were.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "daemon/config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  irslam::DaemonSettings o;
  const std::string before = irslam::DumpConfig(o);
  std::string error;
  if (!irslam::ParseConfig(std::string_view(reinterpret_cast<const char*>(data), size), &o, &error)) {
    if (irslam::DumpConfig(o) != before || error.empty() || error.find('\n') != std::string::npos) std::abort();
  }
  return 0;
}
