// The layout of the configuration file: which section holds which component's
// option table (types/options.h), plus the few keys whose values are not plain
// numbers, flags or strings (sensor mounts, the IR table, GPIO lines). One walk
// over this layout parses a file, prints the effective configuration and writes
// the shipped, commented daemon/irslamd.conf — so each key is written once, in
// its component's table.
#ifndef IRSLAM_DAEMON_CONFIG_SCHEMA_H_
#define IRSLAM_DAEMON_CONFIG_SCHEMA_H_

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "io/option_json.h"
#include "daemon/daemon_settings.h"
#include "types/options.h"

namespace irslam::config {

// A key whose value is structured (an array or an object): read, printed and
// documented by hand. read() returns "" or what is wrong with the value.
struct CustomKey {
  std::string_view name;
  std::string_view doc;
  std::function<std::string(const nlohmann::json&)> read;
  std::function<nlohmann::json()> dump;
};

// What walks the layout. Section() opens a (sub)section, End() closes it; Keys()
// binds one component's table to its options struct.
class Visitor {
 public:
  virtual ~Visitor() = default;
  virtual void Section(std::string_view name, std::string_view doc) = 0;
  virtual void End() = 0;
  virtual void Custom(const CustomKey& key) = 0;
  virtual void Key(const options::Entry& entry) = 0;

  template <class T>
  void Keys(T* object, options::Table<T> table) {
    for (const auto& e : options::Bind(object, table)) Key(e);
  }
};

// Walks every section of the file over s: the daemon's own sections bound to s,
// the core's to s->core (the visitor may read or write s).
void WalkConfig(DaemonSettings* s, Visitor* v);

// Checks that span keys (e.g. the IR table against its ranges): "" or one line.
std::string CheckConfig(const DaemonSettings& s);

}  // namespace irslam::config

#endif  // IRSLAM_DAEMON_CONFIG_SCHEMA_H_
