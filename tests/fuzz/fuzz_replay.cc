// libFuzzer target: arbitrary text as a candump -L log through the line parser, the
// recorder-header parser and the offline replay (irslam-replay's path), with the
// same monotonic-time rule as irslam-replay.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string_view>

#include "daemon/candump_log.h"
#include "daemon/replay.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  std::unique_ptr<irslam::Replay> replay;
  int64_t last = 0;
  size_t from = 0;
  while (from < text.size()) {
    size_t end = text.find('\n', from);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(from, end - from);
    from = end + 1;
    irslam::LogLine l;
    std::string error;
    if (!irslam::ParseLogLine(line, &l, &error)) continue;
    if (l.kind == irslam::LogLine::Kind::kComment) (void)irslam::ParseRecordHeader(line);
    if (l.kind != irslam::LogLine::Kind::kFrame && l.kind != irslam::LogLine::Kind::kForeign) continue;
    if (!replay) {
      replay = std::make_unique<irslam::Replay>(irslam::robot::DefaultCoreOptions(), l.stamp_ns, 1.0);
      last = l.stamp_ns;
    }
    if (l.stamp_ns < last) continue;  // irslam-replay refuses it
    last = l.stamp_ns;
    replay->Feed(l);
  }
  return 0;
}
