// libFuzzer target: world files (contracts §1) as irslam-sim reads them.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "sim/world.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string error;
  (void)irslam::sim::ParseWorld(std::string_view(reinterpret_cast<const char*>(data), size), &error);
  return 0;
}
