// Reading and printing JSON objects through option tables (types/options.h): the
// one place where a key's type and bounds are checked, for the daemon's config
// file and the simulator's world files alike.
#ifndef IRSLAM_IO_OPTION_JSON_H_
#define IRSLAM_IO_OPTION_JSON_H_

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "types/options.h"

namespace irslam::options {

// One table entry bound to a member of one object, type-erased.
struct Entry {
  std::string_view name, unit, doc;
  double lo = 0, hi = 0;
  enum class Kind { kNumber, kInt, kBool, kString } kind = Kind::kNumber;
  double* number = nullptr;
  int* integer = nullptr;
  bool* flag = nullptr;
  std::string* text = nullptr;
};

template <class T>
std::vector<Entry> Bind(T* object, Table<T> table) {
  std::vector<Entry> out;
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
    out.push_back(e);
  }
  return out;
}

// Sets the entry from v: "" or what is wrong (" must be a number", " must be in
// [lo, hi] (got x)", ...), to be put after the key's name.
std::string ReadEntry(const nlohmann::json& v, const Entry& e);
// The entry's current value.
nlohmann::json EntryValue(const Entry& e);
// Numbers as the messages and documents print them (%.12g).
std::string FormatNumber(double d);

// Reads a whole JSON object through entries: unknown keys are an error ("PATH.KEY
// is not a known key"). *error gets the first problem as "PATH.KEY what".
bool ReadObject(const nlohmann::json& object, std::string_view path, const std::vector<Entry>& entries,
                std::string* error);

}  // namespace irslam::options

#endif  // IRSLAM_IO_OPTION_JSON_H_
