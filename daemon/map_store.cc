#include "daemon/map_store.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <boost/crc.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>

#include "daemon/map_validate.h"
#include "io/file_io.h"
#include "io/json_text.h"

namespace irslam {
namespace {

constexpr const char* kFormat = "irslam-map";
constexpr int kVersion = 1;

std::string Crc32Hex(const std::string& text) {
  boost::crc_32_type crc;
  crc.process_bytes(text.data(), text.size());
  char buf[9];
  std::snprintf(buf, sizeof buf, "%08x", crc.checksum());
  return buf;
}

std::string Errno(const std::string& what) { return what + ": " + std::strerror(errno); }

bool WriteAll(int fd, const std::string& text) {
  size_t off = 0;
  while (off < text.size()) {
    const ssize_t n = ::write(fd, text.data() + off, text.size() - off);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    off += static_cast<size_t>(n);
  }
  return true;
}

}  // namespace

std::string EncodeMapFile(const StoredMap& m) {
  const std::string body = m.map.dump();
  nlohmann::json j = {{"format", kFormat}, {"version", kVersion}, {"seq", m.seq},
                      {"reason", m.reason}, {"map", m.map}, {"crc32", Crc32Hex(body)}};
  return j.dump() + "\n";
}

std::optional<StoredMap> DecodeMapFile(const std::string& text, std::string* error) {
  std::string why;
  std::optional<nlohmann::json> parsed = ParseJsonText(text, &why);
  if (!parsed) {
    *error = why.rfind("nested", 0) == 0 ? "map file " + why : "not valid JSON (torn or corrupt)";
    return std::nullopt;
  }
  nlohmann::json& j = *parsed;
  const auto is = [&j](const char* key, bool (nlohmann::json::*type)() const noexcept) {
    return j.contains(key) && (j[key].*type)();
  };
  if (!j.is_object() || !is("format", &nlohmann::json::is_string) || j["format"] != kFormat) {
    *error = "not an irslam map file";
    return std::nullopt;
  }
  if (!is("version", &nlohmann::json::is_number_integer)) {
    *error = "map file version is not an integer";
    return std::nullopt;
  }
  if (j["version"] != kVersion) {
    *error = "map file version " + j["version"].dump() + " is not supported";
    return std::nullopt;
  }
  if (!is("map", &nlohmann::json::is_object) || !is("crc32", &nlohmann::json::is_string) ||
      !is("seq", &nlohmann::json::is_number_unsigned)) {
    *error = "map file lacks map, seq or crc32";
    return std::nullopt;
  }
  // reason is outside the checksum: its type is checked like everything else.
  if (j.contains("reason") && !j["reason"].is_string()) {
    *error = "map file reason is not a string";
    return std::nullopt;
  }
  if (Crc32Hex(j["map"].dump()) != j["crc32"].get<std::string>()) {
    *error = "map file checksum does not match (corrupt)";
    return std::nullopt;
  }
  if (!ValidateMapBody(j["map"], &why)) {
    *error = "map file content does not check out: " + why;
    return std::nullopt;
  }
  StoredMap m;
  m.seq = j["seq"].get<uint64_t>();
  m.reason = j.contains("reason") ? j["reason"].get<std::string>() : "";
  m.map = std::move(j["map"]);
  return m;
}

std::optional<StoredMap> MapStore::Load(std::string* error) {
  error->clear();
  if (DIR* d = ::opendir(dir_.c_str())) {
    // Temporary files of a save that never finished: the map it was writing is lost
    // (the previous one is intact), the file itself is garbage.
    while (dirent* e = ::readdir(d)) {
      if (std::strncmp(e->d_name, "map.json.tmp", 12) == 0) ::unlinkat(::dirfd(d), e->d_name, 0);
    }
    ::closedir(d);
  }
  struct stat st {};
  if (::lstat(path().c_str(), &st) != 0) {
    if (errno != ENOENT) *error = Errno("map: cannot read " + path());
    return std::nullopt;  // ENOENT: no map yet
  }
  std::string text, why;
  std::optional<StoredMap> m;
  if (ReadRegularFile(path(), kMaxMapFileBytes, &text, &why)) m = DecodeMapFile(text, &why);
  if (!m) {
    const std::string aside = path() + ".corrupt-" + std::to_string(::time(nullptr));
    if (::rename(path().c_str(), aside.c_str()) == 0) {
      *error = "map: " + path() + ": " + why + "; kept aside as " + aside;
    } else {
      *error = "map: " + path() + ": " + why + "; " + Errno("cannot move it aside");
    }
    return std::nullopt;
  }
  return m;
}

bool MapStore::Save(const StoredMap& m, std::string* error) {
  if (::mkdir(dir_.c_str(), 0750) != 0 && errno != EEXIST) {
    *error = Errno("map: cannot create " + dir_);
    return false;
  }
  const int dfd = ::open(dir_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd < 0) {
    *error = Errno("map: cannot open " + dir_);
    return false;
  }
  const bool ok = SaveIn(dfd, EncodeMapFile(m), error);
  ::close(dfd);
  return ok;
}

bool MapStore::SaveIn(int dfd, const std::string& text, std::string* error) {
  const std::string name = "map.json.tmp" + std::to_string(::getpid());
  const std::string tmp = dir_ + "/" + name;
  // Created here and now, never an existing file or a symlink's target; a leftover
  // of that name (a crash, or something planted) is removed first, not followed.
  constexpr int kFlags = O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC;
  int fd = ::openat(dfd, name.c_str(), kFlags, 0640);
  if (fd < 0 && errno == EEXIST && ::unlinkat(dfd, name.c_str(), 0) == 0) {
    fd = ::openat(dfd, name.c_str(), kFlags, 0640);
  }
  if (fd < 0) {
    *error = Errno("map: cannot create " + tmp);
    return false;
  }
  if (!WriteAll(fd, text) || ::fsync(fd) != 0) {
    *error = Errno("map: cannot write " + tmp);
    ::close(fd);
    ::unlinkat(dfd, name.c_str(), 0);
    return false;
  }
  if (::close(fd) != 0) {
    *error = Errno("map: cannot write " + tmp);
    ::unlinkat(dfd, name.c_str(), 0);
    return false;
  }
  if (::renameat(dfd, name.c_str(), dfd, "map.json") != 0) {
    *error = Errno("map: cannot rename " + tmp + " to " + path());
    ::unlinkat(dfd, name.c_str(), 0);
    return false;
  }
  ::fsync(dfd);  // the rename itself must reach the disk too
  return true;
}

}  // namespace irslam
