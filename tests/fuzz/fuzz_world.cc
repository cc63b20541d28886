// libFuzzer target: world files (contracts §1) as irslam-sim reads them
// (sim/world.h ParseWorld): the JSON parse, the option tables, unknown keys,
// the room outline, boxes and the start pose and the checks that reject an
// impossible world. A rejection is a one-line error; any crash, sanitizer report
// or escaping exception is a bug.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "sim/world.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string error;
  if (!irslam::sim::ParseWorld(std::string_view(reinterpret_cast<const char*>(data), size), &error) &&
      (error.empty() || error.find('\n') != std::string::npos)) {
    std::abort();
  }
  return 0;
}
