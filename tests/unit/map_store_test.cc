// The map on disk (daemon/map_store.h): atomic saves, checks on load, bad files
// kept aside and never used.
#include <gtest/gtest.h>

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
           {"lines", {{{"id", 1}, {"rho", 0.5}, {"theta", 1.5707963}, {"cov", {{1e-4, 0}, {0, 1e-5}}}}}},
           {"objects", nlohmann::json::array()}};
  return m;
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

TEST(MapStoreTest, AnUnwritableDirectoryIsOneLine) {
  MapStore store("/proc/irslam-cannot-be-here");
  std::string error;
  EXPECT_FALSE(store.Save(Sample(1), &error));
  EXPECT_EQ(error.rfind("map: cannot create /proc/irslam-cannot-be-here: ", 0), 0u) << error;
}

}  // namespace
}  // namespace irslam
