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
#include <fstream>
#include <sstream>

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
  nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded()) {
    *error = "not valid JSON (torn or corrupt)";
    return std::nullopt;
  }
  if (!j.is_object() || j.value("format", "") != kFormat) {
    *error = "not an irslam map file";
    return std::nullopt;
  }
  if (j.value("version", 0) != kVersion) {
    *error = "map file version " + std::to_string(j.value("version", 0)) + " is not supported";
    return std::nullopt;
  }
  if (!j.contains("map") || !j["map"].is_object() || !j.contains("crc32") || !j["crc32"].is_string() ||
      !j.contains("seq") || !j["seq"].is_number_unsigned()) {
    *error = "map file lacks map, seq or crc32";
    return std::nullopt;
  }
  if (Crc32Hex(j["map"].dump()) != j["crc32"].get<std::string>()) {
    *error = "map file checksum does not match (corrupt)";
    return std::nullopt;
  }
  StoredMap m;
  m.seq = j["seq"].get<uint64_t>();
  m.reason = j.value("reason", "");
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
  std::ifstream in(path());
  if (!in) return std::nullopt;  // no map yet
  std::stringstream ss;
  ss << in.rdbuf();
  std::string why;
  auto m = DecodeMapFile(ss.str(), &why);
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
  const std::string text = EncodeMapFile(m);
  const std::string tmp = path() + ".tmp" + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0640);
  if (fd < 0) {
    *error = Errno("map: cannot write " + tmp);
    return false;
  }
  if (!WriteAll(fd, text) || ::fsync(fd) != 0) {
    *error = Errno("map: cannot write " + tmp);
    ::close(fd);
    ::unlink(tmp.c_str());
    return false;
  }
  ::close(fd);
  if (::rename(tmp.c_str(), path().c_str()) != 0) {
    *error = Errno("map: cannot rename " + tmp + " to " + path());
    ::unlink(tmp.c_str());
    return false;
  }
  // The rename itself must reach the disk too.
  const int dfd = ::open(dir_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
  return true;
}

}  // namespace irslam
