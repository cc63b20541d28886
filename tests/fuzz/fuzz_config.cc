// libFuzzer target: irslamd config files (JSON with comments, daemon/config.h
// ParseConfig, exactly as LoadConfigFile and SIGHUP run it on a file's text):
// the comment stripping and depth-capped parse, every section's option table
// (types, bounds, unknown keys), the custom keys (sensor mounts, the IR table,
// GPIO lines) and the cross-key checks (config::CheckConfig).
// A rejected config must leave the options exactly as they were, every key the
// schema walk visits (the walk DumpConfig prints), and say why in one line.
// Speed: the defaults' snapshot is taken once, and the comparison reads the
// values through the same walk instead of printing the whole config as JSON
// twice per input (that was 56 % of the time).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>

#include "daemon/config.h"
#include "daemon/config_schema.h"

namespace {

// Every option's value (raw bytes for numbers: a NaN left alone compares equal),
// in the order of the schema walk, with its section and key names.
class Snapshot : public irslam::config::Visitor {
 public:
  static std::string Of(const irslam::DaemonSettings& settings) {
    irslam::DaemonSettings s = settings;
    Snapshot v;
    irslam::config::WalkConfig(&s, &v);
    return std::move(v.out_);
  }
  void Section(std::string_view name, std::string_view) override { Put("{", name); }
  void End() override { out_ += '}'; }
  void Custom(const irslam::config::CustomKey& key) override {
    Put("c", key.name);
    out_ += key.dump().dump();
  }
  void Key(const irslam::options::Entry& e) override {
    using Kind = irslam::options::Entry::Kind;
    Put("k", e.name);
    switch (e.kind) {
      case Kind::kNumber: Raw(*e.number); break;
      case Kind::kInt: Raw(*e.integer); break;
      case Kind::kBool: Raw(*e.flag); break;
      case Kind::kString: Put("s", *e.text); break;
    }
  }

 private:
  void Put(const char* tag, std::string_view text) {
    out_ += tag;
    Raw(text.size());
    out_.append(text.data(), text.size());
  }
  template <class T>
  void Raw(const T& v) {
    char bytes[sizeof v];
    std::memcpy(bytes, &v, sizeof v);
    out_.append(bytes, sizeof v);
  }
  std::string out_;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string defaults = Snapshot::Of(irslam::DaemonSettings());
  irslam::DaemonSettings o;
  std::string error;
  if (!irslam::ParseConfig(std::string_view(reinterpret_cast<const char*>(data), size), &o, &error)) {
    if (Snapshot::Of(o) != defaults || error.empty() || error.find('\n') != std::string::npos) std::abort();
  }
  return 0;
}
