// The map on disk (the daemon's state directory, default /var/lib/irslam): saved
// atomically (temporary file, fsync, rename, fsync of the directory) so that a
// crash or power loss at any moment leaves either the previous or the new map,
// never a torn one; loaded at start; a file that does not check out (not a
// regular file, larger than kMaxMapFileBytes, torn, nested too deep, corrupt,
// foreign, wrong JSON types, a map body that fails daemon/map_validate.h) is
// moved aside as map.json.corrupt-<seconds> and never used. The temporary file
// is created with O_EXCL | O_NOFOLLOW in the state directory itself, so a planted
// symlink is never followed (a leftover of the same name is unlinked first).
//
// File: {"format": "irslam-map", "version": 1, "seq": N, "reason": "...",
//        "map": {contracts §4}, "crc32": "<8 hex digits of CRC-32 over map.dump()>"}
#ifndef IRSLAM_DAEMON_MAP_STORE_H_
#define IRSLAM_DAEMON_MAP_STORE_H_

#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace irslam {

// A map file larger than this is not read (a 2-hour mission's file is ~1 MB).
inline constexpr size_t kMaxMapFileBytes = 64u << 20;

struct StoredMap {
  uint64_t seq = 0;      // saves since the state directory was new
  std::string reason;    // "model", "stop", "shutdown"
  nlohmann::json map;    // contracts §4
};

// Pure: the file's text for a map, and the map back from a file's text
// (nullopt and a one-line *error when it does not check out).
std::string EncodeMapFile(const StoredMap& m);
std::optional<StoredMap> DecodeMapFile(const std::string& text, std::string* error);

class MapStore {
 public:
  explicit MapStore(std::string dir) : dir_(std::move(dir)) {}

  // Loads dir/map.json if there is one. A file that does not check out is moved
  // aside (*error says so and where); leftover temporary files are removed.
  std::optional<StoredMap> Load(std::string* error);
  // Writes dir/map.json atomically (creating dir if needed); false + *error.
  bool Save(const StoredMap& m, std::string* error);

  std::string path() const { return dir_ + "/map.json"; }
  const std::string& dir() const { return dir_; }

 private:
  bool SaveIn(int dir_fd, const std::string& text, std::string* error);

  std::string dir_;
};

}  // namespace irslam

#endif  // IRSLAM_DAEMON_MAP_STORE_H_
