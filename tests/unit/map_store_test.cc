// The map on disk (daemon/map_store.h): atomic saves, checks on load, bad files
// kept aside and never used.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <boost/crc.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>

#include "daemon/map_store.h"
#include "tests/testing/process.h"

namespace irslam {
namespace {

StoredMap Sample(uint64_t seq) {
  StoredMap m;
  m.seq = seq;
  m.reason = "model";
  m.map = {{"frame", "map"},
           {"state", "done"},
           {"pose", {0.1, 0.2, 0.3}},
           {"lines",
            {{{"id", 1}, {"rho", 0.5}, {"theta", 1.5707963}, {"cov", {{1e-4, 0}, {0, 1e-5}}},
              {"p0", {0.0, 0.5}}, {"p1", {2.0, 0.5}}, {"length", 2.0}}}},
           {"room", {{"walls", {{"bottom", {1}}, {"left", nlohmann::json::array()}}}, {"box", nullptr}}},
           {"objects", {{{"id", 1}, {"kind", "free"}, {"lines", {1}}, {"complete", true}, {"box", {0, 0, 1, 1}}}}},
           {"trajectory", {{0.0, 0.0, 0.0, 0.0}, {0.5, 0.1, 0.0, 0.0}}}};
  return m;
}

// A file with a correct checksum over whatever map body is given, and the header
// members as given (to build files that are valid JSON but wrong in type).
std::string FileWith(const nlohmann::json& map, nlohmann::json header = nlohmann::json::object()) {
  boost::crc_32_type crc;
  const std::string body = map.dump();
  crc.process_bytes(body.data(), body.size());
  char hex[9];
  std::snprintf(hex, sizeof hex, "%08x", crc.checksum());
  nlohmann::json j = {{"format", "irslam-map"}, {"version", 1}, {"seq", 3}, {"reason", "stop"},
                      {"map", map}, {"crc32", hex}};
  j.merge_patch(header);
  return j.dump();
}

TEST(MapStoreTest, RoundTripsAndChecksTheChecksum) {
  const std::string text = EncodeMapFile(Sample(7));
  std::string error;
  auto back = DecodeMapFile(text, &error);
  ASSERT_TRUE(back) << error;
  EXPECT_EQ(back->seq, 7u);
  EXPECT_EQ(back->reason, "model");
  EXPECT_EQ(back->map, Sample(7).map);  // numbers survive exactly
  // One digit changed inside the map: still JSON, but the checksum says no.
  std::string bad = text;
  bad[bad.find("0.5")] = '0';
  bad[bad.find("0.5") + 2] = '6';
  EXPECT_FALSE(DecodeMapFile(bad, &error));
  EXPECT_EQ(error, "map file checksum does not match (corrupt)");
  // Torn: the end of the file missing.
  EXPECT_FALSE(DecodeMapFile(text.substr(0, text.size() / 2), &error));
  EXPECT_EQ(error, "not valid JSON (torn or corrupt)");
  EXPECT_FALSE(DecodeMapFile(R"({"format":"something-else"})", &error));
  EXPECT_EQ(error, "not an irslam map file");
  EXPECT_FALSE(DecodeMapFile(R"({"format":"irslam-map","version":2})", &error));
  EXPECT_EQ(error, "map file version 2 is not supported");
}

TEST(MapStoreTest, SavesAtomicallyLoadsAndKeepsBadFilesAside) {
  const std::string dir = testing::MakeTempDir() + "/state";  // created by the first save
  MapStore store(dir);
  std::string error;
  EXPECT_FALSE(store.Load(&error));
  EXPECT_EQ(error, "");  // no map yet is not an error
  ASSERT_TRUE(store.Save(Sample(1), &error)) << error;
  ASSERT_TRUE(store.Save(Sample(2), &error)) << error;
  // A save that died half-way left its temporary file: removed on load, the map intact.
  std::ofstream(dir + "/map.json.tmp4242") << "{\"format\":\"irsl";
  auto m = store.Load(&error);
  ASSERT_TRUE(m) << error;
  EXPECT_EQ(m->seq, 2u);
  EXPECT_FALSE(std::filesystem::exists(dir + "/map.json.tmp4242"));
  // A torn map.json: detected, moved aside, not loaded.
  const std::string text = EncodeMapFile(Sample(3));
  std::ofstream(dir + "/map.json") << text.substr(0, 40);
  EXPECT_FALSE(store.Load(&error));
  EXPECT_NE(error.find("not valid JSON (torn or corrupt); kept aside as " + dir + "/map.json.corrupt-"),
            std::string::npos)
      << error;
  EXPECT_FALSE(std::filesystem::exists(dir + "/map.json"));
  int aside = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    aside += e.path().filename().string().rfind("map.json.corrupt-", 0) == 0;
  }
  EXPECT_EQ(aside, 1);
  std::filesystem::remove_all(std::filesystem::path(dir).parent_path());
}

// Issue 12 B3: wrong JSON types in the header aborted the daemon (SIGABRT at
// start, a crash loop under Restart=on-failure); a CRC-valid map with "lines": 5
// was served and `irslamctl map --svg` aborted.
TEST(MapStoreTest, WrongTypesAnywhereAreAOneLineErrorNeverAnAbort) {
  std::string error;
  ASSERT_TRUE(DecodeMapFile(FileWith(Sample(1).map), &error)) << error;
  const std::vector<std::pair<nlohmann::json, std::string>> headers = {
      {{{"format", 1}}, "not an irslam map file"},
      {{{"version", "1"}}, "map file version is not an integer"},
      {{{"version", 1.5}}, "map file version is not an integer"},
      {{{"reason", 5}}, "map file reason is not a string"},
      {{{"seq", -1}}, "map file lacks map, seq or crc32"},
      {{{"seq", "3"}}, "map file lacks map, seq or crc32"},
      {{{"crc32", 12345678}}, "map file lacks map, seq or crc32"},
  };
  for (const auto& [header, message] : headers) {
    EXPECT_FALSE(DecodeMapFile(FileWith(Sample(1).map, header), &error)) << header;
    EXPECT_EQ(error, message) << header;
  }
  EXPECT_FALSE(DecodeMapFile("[1, 2]", &error));
  EXPECT_EQ(error, "not an irslam map file");
  EXPECT_FALSE(DecodeMapFile(std::string(100000, '[') + std::string(100000, ']'), &error));
  EXPECT_EQ(error, "map file nested deeper than 64 levels");
  // The map body, checksum and all correct, but not a §4 map.
  const std::vector<std::pair<std::string, std::string>> bodies = {
      {R"("lines": 5)", "map.lines: missing or not an array"},
      {R"("frame": 1)", "map.frame: missing or not a string"},
      {R"("pose": [0, 0])", "map.pose: not an array of 3 numbers"},
      {R"("pose_cov": [[1, 0, 0], [0, 1, 0], [0, 0, "x"]])", "map.pose_cov: not a 3x3 matrix of numbers"},
      {R"("lines": [{"id": 1, "rho": 0, "theta": 0, "cov": [[1, 0], [0, 1]], "p0": [0, 0], "p1": [1]}])",
       "map.lines[0].p1: not an array of 2 numbers"},
      {R"("lines": [7])", "map.lines[0]: not an object"},
      {R"("objects": [{"id": "a", "kind": "free", "lines": []}])", "map.objects[0].id: not an integer"},
      {R"("objects": [{"id": 1, "kind": "free", "lines": [], "box": [0, 0, 1]}])",
       "map.objects[0].box: not an array of 4 numbers"},
      {R"("room": {"walls": {"top": ["1"]}})", "map.room.walls.top: not an array of integers"},
      {R"("room": {"box": 3})", "map.room.box: not null or an array of 4 numbers"},
      {R"("trajectory": [[0, 0, 0]])", "map.trajectory[0]: not an array of 4 numbers"},
  };
  for (const auto& [member, message] : bodies) {
    nlohmann::json map = Sample(1).map;
    map.merge_patch(nlohmann::json::parse("{" + member + "}"));
    EXPECT_FALSE(DecodeMapFile(FileWith(map), &error)) << member;
    EXPECT_EQ(error, "map file content does not check out: " + message) << member;
  }
}

int FilesStartingWith(const std::string& dir, const std::string& prefix) {
  int n = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) n += e.path().filename().string().rfind(prefix, 0) == 0;
  return n;
}

// Issue 12 B3: a FIFO at the map path hung start-up; every invalid file is put aside.
TEST(MapStoreTest, AFifoOrAWrongTypedFileIsPutAsideAtOnceAndNeverLoaded) {
  const std::string dir = testing::MakeTempDir();
  MapStore store(dir);
  std::string error;
  ASSERT_EQ(::mkfifo((dir + "/map.json").c_str(), 0600), 0);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_FALSE(store.Load(&error));
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(2));
  EXPECT_NE(error.find("not a regular file; kept aside as " + dir + "/map.json.corrupt-"), std::string::npos) << error;
  EXPECT_FALSE(std::filesystem::exists(dir + "/map.json"));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directory(dir);
  std::ofstream(dir + "/map.json") << FileWith(Sample(1).map, {{"reason", 5}});
  EXPECT_FALSE(store.Load(&error));
  EXPECT_NE(error.find("map file reason is not a string; kept aside as "), std::string::npos) << error;
  EXPECT_EQ(FilesStartingWith(dir, "map.json.corrupt-"), 1);
  EXPECT_FALSE(store.Load(&error));  // the next start finds no map: no crash loop
  EXPECT_EQ(error, "");
  std::filesystem::remove_all(dir);
}

// Issue 12 B4: the temporary file was opened without O_NOFOLLOW/O_EXCL, so a
// planted symlink made the daemon overwrite its target.
TEST(MapStoreTest, APlantedSymlinkAtTheTemporaryNameIsNeverFollowed) {
  const std::string dir = testing::MakeTempDir();
  const std::string victim = dir + "/victim";
  std::ofstream(victim) << "precious\n";
  std::filesystem::create_directory(dir + "/state");
  const std::string tmp = dir + "/state/map.json.tmp" + std::to_string(::getpid());
  std::filesystem::create_symlink(victim, tmp);
  MapStore store(dir + "/state");
  std::string error;
  ASSERT_TRUE(store.Save(Sample(4), &error)) << error;
  EXPECT_EQ(testing::ReadFile(victim), "precious\n");
  EXPECT_TRUE(std::filesystem::is_regular_file(std::filesystem::symlink_status(dir + "/state/map.json")));
  EXPECT_FALSE(std::filesystem::exists(std::filesystem::symlink_status(tmp)));
  auto m = store.Load(&error);
  ASSERT_TRUE(m) << error;
  EXPECT_EQ(m->seq, 4u);
  // A leftover regular temporary file of the same name (a crash) is replaced too.
  std::ofstream(tmp) << "half a map";
  ASSERT_TRUE(store.Save(Sample(5), &error)) << error;
  EXPECT_EQ(store.Load(&error)->seq, 5u);
  EXPECT_EQ(FilesStartingWith(dir + "/state", "map.json.tmp"), 0);
  std::filesystem::remove_all(dir);
}

TEST(MapStoreTest, AnUnwritableDirectoryIsOneLine) {
  MapStore store("/proc/irslam-cannot-be-here");
  std::string error;
  EXPECT_FALSE(store.Save(Sample(1), &error));
  EXPECT_EQ(error.rfind("map: cannot create /proc/irslam-cannot-be-here: ", 0), 0u) << error;
}

}  // namespace
}  // namespace irslam
