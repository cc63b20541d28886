// libFuzzer target: the daemon's saved-map file loader (daemon/map_store.h
// DecodeMapFile, with the header checks and daemon/map_validate.h), exactly as
// MapStore::Load runs it on a file's text. A file it accepts must be one every
// reader can use: `irslamctl map --svg` renders it (that aborted on a CRC-valid
// map with "lines": 5), and it encodes and decodes back to itself. A rejection is
// one line. Its body then goes through daemon/core_json.h MapFromJson (the
// daemon's saved map for relocalisation, irslam-sim --map-in): a rejection is one
// line; a map it accepts writes back (ToJson) to JSON it accepts again, unchanged.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "daemon/core_json.h"
#include "daemon/map_store.h"
#include "daemon/map_svg.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::string error;
  const auto m = irslam::DecodeMapFile(text, &error);
  if (!m) {
    if (error.empty() || error.find('\n') != std::string::npos) std::abort();
    return 0;
  }
  nlohmann::json served = m->map;
  served["saved"] = {{"seq", m->seq}, {"reason", m->reason}, {"path", "/var/lib/irslam/map.json"}};
  if (irslam::RenderMapSvg(served, nullptr, nullptr).find("<svg") == std::string::npos) std::abort();
  std::string again;
  const auto back = irslam::DecodeMapFile(irslam::EncodeMapFile(*m), &again);
  if (!back || back->map != m->map || back->seq != m->seq || back->reason != m->reason) std::abort();
  irslam::robot::MapSnapshot typed;
  if (!irslam::MapFromJson(m->map, &typed, &error)) {
    if (error.empty() || error.find('\n') != std::string::npos) std::abort();
    return 0;
  }
  const nlohmann::json written = irslam::ToJson(typed);
  irslam::robot::MapSnapshot again_typed;
  if (!irslam::MapFromJson(written, &again_typed, &error) || irslam::ToJson(again_typed) != written) std::abort();
  return 0;
}
