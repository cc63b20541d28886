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

#include "robot/robot_core.h"
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
  // One entry of a table, type-erased: the entry's metadata and access to its value.
  struct Entry {
    std::string_view name, unit, doc;
    double lo = 0, hi = 0;
    enum class Kind { kNumber, kInt, kBool, kString } kind = Kind::kNumber;
    double* number = nullptr;
    int* integer = nullptr;
    bool* flag = nullptr;
    std::string* text = nullptr;
  };
  virtual void Key(const Entry& entry) = 0;

  template <class T>
  void Keys(T* object, options::Table<T> table) {
    for (const auto& k : table) {
      Entry e{k.name, k.unit, k.doc, k.lo, k.hi};
      if (auto* m = std::get_if<double T::*>(&k.member)) {
        e.kind = Entry::Kind::kNumber, e.number = &(object->**m);
      } else if (auto* i = std::get_if<int T::*>(&k.member)) {
        e.kind = Entry::Kind::kInt, e.integer = &(object->**i);
      } else if (auto* b = std::get_if<bool T::*>(&k.member)) {
        e.kind = Entry::Kind::kBool, e.flag = &(object->**b);
      } else {
        e.kind = Entry::Kind::kString, e.text = &(object->*std::get<std::string T::*>(k.member));
      }
      Key(e);
    }
  }
};

// Walks every section of the file over o (the visitor may read or write o).
void WalkConfig(robot::CoreOptions* o, Visitor* v);

// Checks that span keys (e.g. the IR table against its ranges): "" or one line.
std::string CheckConfig(const robot::CoreOptions& o);

}  // namespace irslam::config

#endif  // IRSLAM_DAEMON_CONFIG_SCHEMA_H_
