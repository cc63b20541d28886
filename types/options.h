// Option tables: each component declares its options struct and, next to it, one
// table of its keys (name, member, bounds, unit, one-line doc). The same table
// drives the config parser (unknown keys rejected), `irslamd --print-config` and
// the shipped, commented daemon/irslamd.conf, so a key is written once.
//
//   struct WallFollowerOptions { double follow_distance_m = 0.3; ... };
//   options::Table<WallFollowerOptions> WallFollowerKeys();   // in the .cc:
//   options::Table<WallFollowerOptions> WallFollowerKeys() {
//     static constexpr options::Key<WallFollowerOptions> kKeys[] = {
//         {"follow_distance_m", &WallFollowerOptions::follow_distance_m, 0.1, 2.0, "m",
//          "distance kept from the wall on the right"},
//     };
//     return kKeys;
//   }
//
// Pure metadata (no parsing here): the config reader lives in daemon/config.cc.
#ifndef IRSLAM_TYPES_OPTIONS_H_
#define IRSLAM_TYPES_OPTIONS_H_

#include <span>
#include <string>
#include <string_view>
#include <variant>

namespace irslam::options {

template <class T>
struct Key {
  std::string_view name;
  // The member the key sets. Integers must be whole numbers within the bounds;
  // bounds are ignored for bool and string members.
  std::variant<double T::*, int T::*, bool T::*, std::string T::*> member;
  double lo = 0;
  double hi = 0;
  std::string_view unit;  // "m", "s", "m/s", "rad", "rad/s", "" for counts and flags
  std::string_view doc;   // one line: what it does
};

template <class T>
using Table = std::span<const Key<T>>;

}  // namespace irslam::options

#endif  // IRSLAM_TYPES_OPTIONS_H_
