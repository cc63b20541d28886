// The map service (daemon/map_service.h): what `map` serves and what is saved,
// and when, under a fake clock.
#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>
#include <filesystem>
#include <fstream>
#include <thread>

#include "daemon/map_service.h"
#include "tests/testing/process.h"

namespace irslam {
namespace {

nlohmann::json MapWithLines(int n, double rho = 0.5) {
  nlohmann::json lines = nlohmann::json::array();
  for (int i = 0; i < n; ++i) {
    lines.push_back({{"id", i + 1},
                     {"rho", rho + i},
                     {"theta", 1.5707963},
                     {"cov", {{1e-4, 0}, {0, 1e-5}}},
                     {"p0", {0.0, rho}},
                     {"p1", {1.0, rho}},
                     {"length", 1.0}});
  }
  return {{"frame", "map"}, {"state", n ? "done" : "idle"}, {"lines", lines}, {"objects", nlohmann::json::array()}};
}

class MapServiceTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = testing::MakeTempDir(); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::unique_ptr<MapService> Make(const std::string& state = "") {
    return std::make_unique<MapService>(state.empty() ? dir_ + "/state" : state, [this] { return now_; });
  }
  // What a fresh store finds on disk.
  std::optional<StoredMap> OnDisk() {
    std::string error;
    return MapStore(dir_ + "/state").Load(&error);
  }
  void Advance(double s) { now_ += std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(s)); }

  std::string dir_;
  WallTime now_ = WallTime(std::chrono::hours(10));
  nlohmann::json live_ = MapWithLines(0);
  MapService::MapSource live() {
    return [this] { return MapEncoder([m = live_] { return m; }); };
  }
};

TEST_F(MapServiceTest, ServesTheSavedMapUntilAMissionStartsThenTheLiveOne) {
  auto first = Make();
  first->OnMissionStarted();
  live_ = MapWithLines(3);
  ASSERT_EQ(first->Save("model", live()), SaveResult::kSaved);
  auto next = Make();  // a restart
  next->Load();
  live_ = MapWithLines(0);
  auto served = next->Serve(live());
  EXPECT_EQ(served["lines"].size(), 3u);
  EXPECT_EQ(served["saved"]["seq"], 1);
  EXPECT_EQ(served["saved"]["reason"], "model");
  // Nothing ran: a stop or shutdown saves nothing, the saved map stays.
  EXPECT_EQ(next->Save("shutdown", live(), true), SaveResult::kNothing);
  next->OnMissionStarted();
  live_ = MapWithLines(1);
  EXPECT_EQ(next->Serve(live())["lines"].size(), 1u);
  EXPECT_FALSE(next->Serve(live()).contains("saved"));
}

// Issue 12 B1: a reload after a finished mission replaced the core; `map` then
// served an empty map and the next stop or SIGTERM saved it over the finished one.
TEST_F(MapServiceTest, AReplacedCoresFinishedMapIsKeptServedAndNeverOverwrittenByAnEmptyOne) {
  auto maps = Make();
  maps->OnMissionStarted();
  live_ = MapWithLines(5);
  ASSERT_EQ(maps->Save("model", live()), SaveResult::kSaved);
  const nlohmann::json finished = live_;
  Advance(60);
  maps->OnCoreReplaced([finished] { return finished; });
  live_ = MapWithLines(0);  // the new core knows nothing
  EXPECT_EQ(maps->Serve(live())["lines"].size(), 5u);
  EXPECT_EQ(maps->Save("stop", live()), SaveResult::kUnchanged);
  EXPECT_EQ(maps->Save("shutdown", live(), true), SaveResult::kUnchanged);
  ASSERT_TRUE(OnDisk());
  EXPECT_EQ(OnDisk()->map["lines"].size(), 5u);
  EXPECT_EQ(OnDisk()->seq, 1u);
  // A mission on the new core: its map is served and saved from then on.
  maps->OnMissionStarted();
  live_ = MapWithLines(1);
  EXPECT_EQ(maps->Serve(live())["lines"].size(), 1u);
  Advance(60);
  EXPECT_EQ(maps->Save("stop", live()), SaveResult::kSaved);
  EXPECT_EQ(OnDisk()->map["lines"].size(), 1u);
}

TEST_F(MapServiceTest, AnUnsavedMapOfAReplacedCoreIsSavedThen) {
  auto maps = Make();
  maps->OnMissionStarted();
  live_ = MapWithLines(2);
  ASSERT_EQ(maps->Save("stop", live()), SaveResult::kSaved);
  live_ = MapWithLines(4);  // the mission went on after that save
  maps->OnCoreReplaced([m = live_] { return m; });
  EXPECT_EQ(maps->StatusJson()["last_result"], "saved");
  EXPECT_EQ(OnDisk()->map["lines"].size(), 4u);
  EXPECT_EQ(OnDisk()->reason, "reload");
}

TEST_F(MapServiceTest, AStopStormWritesOnceAndChangedMapsAtMostOncePerInterval) {
  auto maps = Make();
  maps->OnMissionStarted();
  live_ = MapWithLines(2);
  ASSERT_EQ(maps->Save("stop", live()), SaveResult::kSaved);
  for (int i = 0; i < 500; ++i) {
    Advance(0.001);
    ASSERT_EQ(maps->Save("stop", live()), SaveResult::kUnchanged);
  }
  EXPECT_EQ(maps->StatusJson()["saves"], 1);
  EXPECT_EQ(maps->StatusJson()["unchanged"], 500);
  // The map changes between stops: one write per interval, the rest deferred.
  live_ = MapWithLines(3);
  EXPECT_EQ(maps->Save("stop", live()), SaveResult::kDeferred);
  EXPECT_TRUE(maps->save_pending());
  Advance(MapService::kDefaultMinIntervalS - 0.6);  // 0.5 s + 4.4 s since the write
  maps->Poll(live());
  EXPECT_EQ(OnDisk()->map["lines"].size(), 2u);
  Advance(0.2);
  maps->Poll(live());
  EXPECT_FALSE(maps->save_pending());
  EXPECT_EQ(OnDisk()->map["lines"].size(), 3u);
  EXPECT_EQ(maps->StatusJson()["saves"], 2);
  // The final save at shutdown is never deferred.
  live_ = MapWithLines(4);
  EXPECT_EQ(maps->Save("shutdown", live(), /*final=*/true), SaveResult::kSaved);
  EXPECT_EQ(OnDisk()->map["lines"].size(), 4u);
  EXPECT_EQ(OnDisk()->reason, "shutdown");
}

// Issue 12 B2: a failed save was not reported.
TEST_F(MapServiceTest, AFailedSaveIsReportedAndTheNextOneTriesAgain) {
  std::ofstream(dir_ + "/plain-file") << "x";
  auto maps = Make(dir_ + "/plain-file/state");  // cannot be created, even by root
  maps->OnMissionStarted();
  live_ = MapWithLines(2);
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(maps->Save("stop", live()), SaveResult::kFailed);
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(log.rfind("<3>irslamd: map: cannot create " + dir_ + "/plain-file/state: ", 0), 0u) << log;
  const auto s = maps->StatusJson();
  EXPECT_EQ(s["save_errors"], 1);
  EXPECT_EQ(s["last_result"], "failed");
  EXPECT_EQ(s["error"].get<std::string>().rfind("map: cannot create", 0), 0u) << s;
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(maps->Save("shutdown", live(), true), SaveResult::kFailed);  // not "unchanged"
  ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(maps->StatusJson()["save_errors"], 2);
}

// Issue 15: with an io_context the map is encoded and compared on the writer
// thread, never in the caller's (the control tick's); every outcome still comes
// back, "unchanged" and "deferred" included, and a save asked for while one is
// in flight is answered by its own outcome.
TEST_F(MapServiceTest, OnTheWriterThreadTheMapIsEncodedComparedAndWrittenAndEveryOutcomeComesBack) {
  boost::asio::io_context io;
  MapService maps(dir_ + "/state", [this] { return now_; }, MapService::kDefaultMinIntervalS, &io);
  std::vector<SaveResult> outcomes;
  maps.set_written([&](SaveResult r) { outcomes.push_back(r); });
  const auto control = std::this_thread::get_id();
  int encoded = 0, encoded_here = 0;
  const auto source = [&] {
    return [&] {
      return MapEncoder([&, m = live_] {
        ++encoded;
        encoded_here += std::this_thread::get_id() == control;
        return m;
      });
    };
  };
  const auto wait = [&](size_t n) {
    for (int i = 0; i < 500 && outcomes.size() < n; ++i) {
      io.run_for(std::chrono::milliseconds(10));
      io.restart();
    }
    return outcomes.size() == n;
  };
  maps.OnMissionStarted();
  live_ = MapWithLines(2);
  EXPECT_EQ(maps.Save("model", source()), SaveResult::kQueued);
  EXPECT_EQ(encoded_here, 0);  // not in the caller (the writer may have encoded it already: a race to count it)
  ASSERT_TRUE(wait(1));
  EXPECT_EQ(outcomes.back(), SaveResult::kSaved);
  EXPECT_EQ(OnDisk()->map["lines"].size(), 2u);
  Advance(1);
  EXPECT_EQ(maps.Save("stop", source()), SaveResult::kQueued);
  ASSERT_TRUE(wait(2));
  EXPECT_EQ(outcomes.back(), SaveResult::kUnchanged);
  // Changed, 2 s after the write: deferred, then written by Poll in its time.
  live_ = MapWithLines(3);
  Advance(1);
  EXPECT_EQ(maps.Save("cell", source()), SaveResult::kQueued);
  ASSERT_TRUE(wait(3));
  EXPECT_EQ(outcomes.back(), SaveResult::kDeferred);
  EXPECT_TRUE(maps.save_pending());
  Advance(MapService::kDefaultMinIntervalS);
  maps.Poll(source());
  ASSERT_TRUE(wait(4));
  EXPECT_EQ(outcomes.back(), SaveResult::kSaved);
  EXPECT_EQ(OnDisk()->map["lines"].size(), 3u);
  EXPECT_EQ(OnDisk()->reason, "cell");
  // Two saves back to back (the second while the first is in flight): one
  // outcome, the second's (the newer map).
  Advance(MapService::kDefaultMinIntervalS);
  live_ = MapWithLines(4);
  EXPECT_EQ(maps.Save("model", source()), SaveResult::kQueued);
  live_ = MapWithLines(5);
  EXPECT_EQ(maps.Save("stop", source(), /*final=*/true), SaveResult::kQueued);
  ASSERT_TRUE(wait(5));
  io.run_for(std::chrono::milliseconds(50));
  EXPECT_EQ(outcomes.size(), 5u);
  EXPECT_EQ(outcomes.back(), SaveResult::kSaved);
  EXPECT_EQ(OnDisk()->map["lines"].size(), 5u);
  EXPECT_EQ(OnDisk()->reason, "stop");
  EXPECT_EQ(encoded, 6);
  EXPECT_EQ(encoded_here, 0);
  const auto s = maps.StatusJson();
  EXPECT_EQ(s["saves"], 4);
  EXPECT_EQ(s["unchanged"], 1);
  EXPECT_EQ(s["deferred"], 1);
  EXPECT_EQ(s["writing"], false);
  // At shutdown: synchronous, in the caller, truthful.
  live_ = MapWithLines(6);
  EXPECT_EQ(maps.Flush("shutdown", source()), SaveResult::kSaved);
  EXPECT_EQ(encoded_here, 1);
  EXPECT_EQ(OnDisk()->map["lines"].size(), 6u);
  EXPECT_EQ(maps.Flush("shutdown", source()), SaveResult::kUnchanged);
}

}  // namespace
}  // namespace irslam
