// Cleaning through the real processes (issue 13): irslam-sim serve + irslamd +
// irslamctl on the loopback bus (vcan0 when IRSLAM_TEST_CAN=vcan0), time-scaled
// (IRSLAM_TEST_TIME_SCALE, default 10). `irslamctl clean` maps the room, cleans
// it and goes home; status shows the progress; the saved map (state dir) carries
// the cells with their done flags, and a kill -9 during cleaning leaves it intact
// with the cells finished before; `stop` + `start`, and a restart after kill -9
// + `start` (relocalising in the saved map), clean only the cells left.
#include <signal.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include "daemon/rpc_client.h"
#include "io/json_text.h"
#include "robot/robot_core.h"
#include "sim/coverage.h"
#include "sim/world.h"
#include "tests/testing/process.h"

namespace irslam {
namespace {

using testing::Process;
using testing::RunCommand;
using Clock = std::chrono::steady_clock;

const std::string kBin = IRSLAM_BINARY_DIR;
const std::string kSrc = IRSLAM_SOURCE_DIR;
const double kScale = [] {
  const char* e = std::getenv("IRSLAM_TEST_TIME_SCALE");
  return e && *e ? std::atof(e) : 10.0;
}();

// A wall-time limit that was chosen for 10x: scaled to the time scale in use.
double WallS(double seconds_at_10x) { return seconds_at_10x * 10.0 / kScale; }

void Sleep(double s) { std::this_thread::sleep_for(std::chrono::duration<double>(s)); }

std::optional<nlohmann::json> ReadJson(const std::string& path) {
  std::string error;
  return ParseJsonText(testing::ReadFile(path), &error);
}

// The saved map's cleaning block, or null while there is no file or the file
// has none (a save before cleaning began). The file is read as it is on disk,
// so keys are checked: operator[] on a const json with a missing key is
// undefined behaviour (it crashed this test once in CI).
nlohmann::json SavedCleaning(const std::string& path) {
  const auto file = ReadJson(path);
  if (!file || !file->is_object() || !file->contains("map")) return nullptr;
  const auto& map = file->at("map");
  if (!map.is_object() || !map.contains("cleaning") || !map.at("cleaning").is_object()) return nullptr;
  return map.at("cleaning");
}

int CellsDone(const nlohmann::json& cleaning) {
  int n = 0;
  for (const auto& c : cleaning.value("cells", nlohmann::json::array())) n += c.value("done", false);
  return n;
}

class CleanE2eTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir();
    const char* env = std::getenv("IRSLAM_TEST_CAN");
    bus_ = env && *env ? env : "unix:" + dir_ + "/bus";
    socket_ = dir_ + "/irslamd.sock";
  }
  void TearDown() override {
    // The simulator's last line counts its stalls (a starved test rig, not the robot).
    if (sim_.running() && sim_.Signal(SIGTERM)) sim_.Wait(5);
    if (HasFailure()) {
      std::fprintf(stderr, "--- sim log\n%s--- daemon log\n%s", testing::ReadFile(dir_ + "/sim.log").c_str(),
                   testing::ReadFile(dir_ + "/daemon.log").c_str());
      // The daemon records the bus ([record]): a failed run replays offline, bit
      // for bit (irslam-replay --config irslamd.conf state/bus.log), so it is kept.
      const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
      const std::string keep = std::filesystem::temp_directory_path().string() + "/irslam-failed-" + info->name();
      std::error_code ec;
      std::filesystem::remove_all(keep, ec);
      std::filesystem::rename(dir_, keep, ec);
      if (!ec) {
        std::fprintf(stderr, "--- the run (bus recording, config, logs) is kept in %s\n", keep.c_str());
        dir_ = keep;
        for (Process* p : {&daemon_, &sim_}) p->Signal(SIGKILL);
        for (Process* p : {&daemon_, &sim_}) p->Wait(5);
        return;
      }
    }
    for (Process* p : {&daemon_, &sim_}) p->Signal(SIGKILL);
    for (Process* p : {&daemon_, &sim_}) p->Wait(5);
    std::filesystem::remove_all(dir_);
  }

  std::string MapFile() const { return dir_ + "/state/map.json"; }

  // The simulator on world, and the daemon with the test rig's config (the
  // controller-silence limit in wall time; the state dir here). The limit is
  // 300 ms of wall time: these tests never silence the controller, and this
  // VM stalls both real-time processes at once now and then (measured
  // 100-133 ms, loop jitter and simulator stall together, on 2026-12-03 in CI
  // and here under a build), which at 100 ms (e2e_test.cc's limit) read as
  // "controller lost" and failed a cleaning test.
  void StartAll(const std::string& world) {
    world_ = kSrc + "/tests/worlds/" + world;
    const nlohmann::json config = {{"controller", {{"timeout_s", std::max(0.3, 0.3 * kScale)}}},
                                   {"state", {{"dir", dir_ + "/state"}}},
                                   {"record", {{"enabled", true}}}};
    std::ofstream(dir_ + "/irslamd.conf") << config.dump(2) << "\n";
    ASSERT_TRUE(sim_.Start({kBin + "/sim/irslam-sim", "serve", "--can", bus_, "--world", world_, "--time-scale",
                            std::to_string(kScale), "--truth-out", dir_ + "/truth.json", "--realtime-priority",
                            testing::kSimRealtimePriority},
                           dir_ + "/sim.log"));
    StartDaemon();
  }

  void StartDaemon() {
    ASSERT_TRUE(daemon_.Start({kBin + "/daemon/irslamd", "--can", bus_, "--socket", socket_, "--time-scale",
                               std::to_string(kScale), "--config", dir_ + "/irslamd.conf"},
                              dir_ + "/daemon.log"));
    for (int i = 0; i < 400; ++i) {
      auto s = Status();
      if (s && (*s)["controller"]["alive"] == true) return;
      Sleep(0.05);
    }
    FAIL() << "daemon never answered or never saw the controller";
  }

  std::optional<nlohmann::json> Status() {
    RpcClient c;
    std::string error;
    if (!c.Connect(socket_, &error)) return std::nullopt;
    return c.Call("status", nlohmann::json::object(), 5, &error);
  }

  int Ctl(const std::vector<std::string>& args, std::string* out, double timeout_s = 30) {
    std::vector<std::string> argv = {kBin + "/daemon/irslamctl", "--socket", socket_};
    argv.insert(argv.end(), args.begin(), args.end());
    return RunCommand(argv, out, timeout_s);
  }

  std::string dir_, bus_, socket_, world_;
  Process sim_, daemon_;
};

// The floors below are a few points under what 3 runs at 10x measured (in the
// comments), on fig17 (3 x 3 m, one cell: ~370 s of robot time, ~40 s wall).
TEST_F(CleanE2eTest, CleanShowsGrowingProgressEndsDoneAndSavesTheCells) {
  StartAll("fig17.json");
  std::string out;
  ASSERT_EQ(Ctl({"clean"}, &out), 0) << out;
  EXPECT_EQ(out.rfind("state: ", 0), 0u) << out;
  std::vector<double> fractions;  // status.cleaning.fraction while in state clean
  bool saw_return_home = false;
  nlohmann::json last;
  const auto end = Clock::now() + std::chrono::duration<double>(WallS(120));
  while (Clock::now() < end) {
    auto s = Status();
    ASSERT_TRUE(s);
    last = *s;
    const std::string state = (*s)["state"];
    ASSERT_NE(state, "fault") << s->dump();
    ASSERT_NE(state, "idle") << s->dump();
    if (state == "clean") {
      ASSERT_TRUE((*s)["cleaning"].is_object()) << s->dump();
      EXPECT_EQ((*s)["cleaning"]["state"], "cleaning");
      fractions.push_back((*s)["cleaning"]["fraction"]);
    }
    saw_return_home |= state == "return_home";
    if (state == "done") break;
    Sleep(0.25);
  }
  ASSERT_EQ(last["state"], "done") << last.dump();
  EXPECT_TRUE(saw_return_home);
  // Progress grows while cleaning (never back), from near nothing to most of the room.
  ASSERT_GE(fractions.size(), 20u) << "cleaning lasted ~270 s of robot time: sampled every 0.25 s wall";
  for (size_t i = 1; i < fractions.size(); ++i) EXPECT_GE(fractions[i], fractions[i - 1] - 1e-12) << i;
  EXPECT_LT(fractions.front(), 0.2);
  EXPECT_GT(fractions.back(), fractions.front() + 0.5);
  const auto& cl = last["cleaning"];
  EXPECT_EQ(cl.at("state"), "done");
  EXPECT_EQ(cl.at("cells_done"), cl.at("cells_total"));
  // Estimated; measured 0.992-0.999 (4 runs), 0.940 and 0.974 in the two
  // sanitizer runs that touched the wall (below).
  EXPECT_GT(cl.at("fraction").get<double>(), 0.90);
  ASSERT_EQ(Ctl({"status"}, &out), 0) << out;
  EXPECT_NE(out.find("cleaning:   done, cells 1/1"), std::string::npos) << out;

  // stop saves the map (deferred while the last cell's save is under 5 s old):
  // the file carries the cleaning with its cells, all done.
  ASSERT_EQ(Ctl({"stop"}, &out), 0) << out;
  std::optional<nlohmann::json> file;
  for (int i = 0; i < 100 && !(file && (*file)["reason"] == "stop"); ++i) {
    Sleep(0.1);
    file = ReadJson(MapFile());
  }
  ASSERT_TRUE(file) << testing::ReadFile(MapFile());
  ASSERT_EQ((*file)["reason"], "stop");
  const auto& saved = (*file)["map"]["cleaning"];
  ASSERT_TRUE(saved.is_object()) << file->dump();
  EXPECT_EQ(saved["state"], "done");
  EXPECT_GT(saved["finished_t"].get<double>(), saved["swept_t"].get<double>());
  ASSERT_GE(saved["cells"].size(), 1u);
  for (const auto& c : saved["cells"]) {
    EXPECT_EQ(c["done"], true);
    EXPECT_GE(c["polygon"].size(), 3u);
  }
  EXPECT_GT(saved["fraction"].get<double>(), 0.90);

  // Against the truth: the body's sweep of the reachable floor while cleaning.
  sim_.Signal(SIGTERM);
  ASSERT_EQ(sim_.Wait(10), 0);
  const auto truth = ReadJson(dir_ + "/truth.json");
  ASSERT_TRUE(truth);
  std::string error;
  const auto world = sim::LoadWorldFile(world_, &error);
  ASSERT_TRUE(world) << error;
  std::vector<TimedPose> traj;
  for (const auto& p : (*truth)["trajectory"]) traj.push_back({p[0], {p[1], p[2], p[3]}});
  const double t0 = saved["started_t"], t1 = saved["swept_t"];
  const sim::CoverageScore cov = sim::ScoreCoverage(*world, robot::DefaultCoreOptions().slam.geometry.radius_m, traj, t0, t1);
  std::fprintf(stderr,
               "clean_e2e: fig17 covered %.1f %% of %.2f m2 (true), %.1f %% estimated, %.0f s cleaning; "
               "simulator stalls %d, longest %.1f ms wall\n",
               100 * cov.fraction, cov.reachable_m2, 100 * saved["fraction"].get<double>(), t1 - t0,
               truth->at("serve").at("stalls").get<int>(), 1000 * truth->at("serve").at("longest_stall_s").get<double>());
  // Measured 0.903-0.917 (3 runs; in process 0.903). Through the processes a
  // run's course differs from period to period with the frames' timing: in
  // the sanitizer build fig17 touched the bottom wall once (then 0.850 and
  // 0.893) in 3 of the runs seen in CI (815af7f, and both attempts of b546dac's
  // local CI), on the way to the first lane point, with a pose ~10 cm off and
  // the right-front beams silent under 20 cm; in process it touches nothing on
  // seeds 1-20. The cleaning's quality (coverage, no contact) is gated in
  // process (clean_test: fig17 there too) and by the campaign subsets; here,
  // that the cleaning through the real processes cleans and touches at most
  // once (docs/reliability.md).
  EXPECT_GT(cov.fraction, 0.80);
  EXPECT_LE((*truth)["collisions"].get<int>(), 1);
}

// fig14 (seven cells): kill -9 once two cells are done and saved. The file is
// intact (the daemon's own check passes on restart) and keeps those cells done.
TEST_F(CleanE2eTest, KillNineDuringCleaningKeepsTheSavedProgressIntact) {
  StartAll("fig14.json");
  std::string out;
  ASSERT_EQ(Ctl({"start", "--mode", "clean"}, &out), 0) << out;
  int saved_done = 0;
  nlohmann::json saved_cleaning;
  const auto end = Clock::now() + std::chrono::duration<double>(WallS(120));
  while (Clock::now() < end && saved_done < 2) {
    auto s = Status();
    ASSERT_TRUE(s);
    ASSERT_NE((*s)["state"], "fault") << s->dump();
    ASSERT_NE((*s)["state"], "done") << "cleaning ended before two cells were saved";
    if (auto cl = SavedCleaning(MapFile()); !cl.is_null()) {
      saved_cleaning = std::move(cl);
      saved_done = CellsDone(saved_cleaning);
    }
    Sleep(0.2);
  }
  ASSERT_GE(saved_done, 2) << "no save with two finished cells; last saved: " << saved_cleaning.dump();
  const auto before = ReadJson(MapFile());
  ASSERT_TRUE(before);
  daemon_.Signal(SIGKILL);
  daemon_.Wait(5);

  // The file parses, is the one written before the kill, and holds the progress.
  const auto after = ReadJson(MapFile());
  ASSERT_TRUE(after) << "torn map file";
  // (const json: operator[] on a missing key is undefined; at() throws, contains() checks.)
  ASSERT_TRUE(after->contains("map") && after->at("map").contains("cleaning")) << after->dump().substr(0, 400);
  EXPECT_EQ(after->value("seq", -1), before->value("seq", -2));
  const auto& cl = after->at("map").at("cleaning");
  std::fprintf(stderr, "clean_e2e: fig14 killed with %d of %zu cells saved done, %.2f m2 (%.1f %%) saved\n",
               CellsDone(cl), cl.at("cells").size(), cl.at("covered_m2").get<double>(), 100 * cl.at("fraction").get<double>());
  EXPECT_EQ(cl.at("state"), "cleaning");
  EXPECT_GE(cl.at("cells").size(), 4u);  // 7 in process (seeds 1-24); the model may be cut otherwise
  EXPECT_GE(CellsDone(cl), 2);
  EXPECT_GT(cl.at("covered_m2").get<double>(), 0.15 * cl.at("total_m2").get<double>());  // two of ~7 cells
  EXPECT_GT(cl.at("fraction").get<double>(), 0.2);
  EXPECT_LT(cl.at("fraction").get<double>(), 0.9);

  // A restarted daemon accepts the file (checksum and all) and serves it.
  StartDaemon();
  ASSERT_EQ(Ctl({"map", "--out", dir_ + "/served.json"}, &out), 0) << out;
  const auto served = ReadJson(dir_ + "/served.json");
  ASSERT_TRUE(served);
  ASSERT_TRUE(served->contains("saved") && served->contains("cleaning")) << served->dump().substr(0, 400);
  EXPECT_EQ(served->at("saved").value("seq", -1), before->value("seq", -2)) << served->dump().substr(0, 400);
  EXPECT_EQ(served->at("cleaning"), cl);
}

// fig16 (four cells; the world that relocalised in 50 of 50 random starts,
// docs/relocalization-results.md): `stop` after the first finished cell and a
// `start` go on with the cells not yet cleaned, in the live map; a kill -9 after
// the second, a restarted daemon and a `start` relocalise in the saved map and
// clean the rest, never the finished cells again, then go home: done.
TEST_F(CleanE2eTest, StopAndStartResumeTheRemainingCellsAndSoDoesARestartAfterKillNine) {
  StartAll("fig16.json");
  std::string out;
  // Waits (wall time for 10x) until the saved map holds at least `cells` done
  // cells and returns its cleaning block; fails on fault or an early end.
  const auto wait_saved = [&](int cells, double wall_s_at_10x) {
    nlohmann::json saved;
    const auto end = Clock::now() + std::chrono::duration<double>(WallS(wall_s_at_10x));
    while (Clock::now() < end) {
      auto s = Status();  // not const: operator[] on a const json with a missing key is undefined
      if (!s) break;
      EXPECT_NE((*s)["state"], "fault") << s->dump();
      EXPECT_NE((*s)["state"], "done") << "cleaning ended before " << cells << " cells were saved";
      if ((*s)["state"] == "fault" || (*s)["state"] == "done") break;
      if (auto cl = SavedCleaning(MapFile()); !cl.is_null()) {
        saved = std::move(cl);
        if (CellsDone(saved) >= cells) return saved;
      }
      Sleep(0.2);
    }
    ADD_FAILURE() << "no save with " << cells << " finished cells; last saved: " << saved.dump();
    return saved;
  };

  ASSERT_EQ(Ctl({"start", "--mode", "clean"}, &out), 0) << out;
  const nlohmann::json first = wait_saved(1, 120);
  ASSERT_GE(CellsDone(first), 1);
  // fig16's model has 4 cells in process (seeds 1-6); through the processes the
  // run differs from period to period and the model may be cut otherwise (6
  // cells in a CI run: an object's P1 was not reached). Stop, kill and resume
  // need at least 3.
  const size_t cells_total = first.at("cells").size();
  ASSERT_GE(cells_total, 3u) << first.dump();

  // stop, then start in the same daemon: cleaning goes on, the done cells stay done.
  ASSERT_EQ(Ctl({"stop"}, &out), 0) << out;
  auto s = Status();
  ASSERT_TRUE(s);
  EXPECT_EQ((*s)["state"], "idle");
  EXPECT_EQ((*s)["cleaning"]["state"], "stopped") << s->dump();
  const int done_at_stop = (*s)["cleaning"]["cells_done"];
  EXPECT_GE(done_at_stop, 1);
  ASSERT_EQ(Ctl({"start", "--mode", "clean"}, &out), 0) << out;
  Sleep(WallS(1.0));
  s = Status();
  ASSERT_TRUE(s);
  EXPECT_EQ((*s)["state"], "clean") << "a start after stop goes on cleaning: " << s->dump();
  // The saved map keeps the plan's inputs (cleaning.planned): while the model is
  // where it was, the resume plans from them (the same cells; in process,
  // RelocTest.StopAndStartInTheLiveMapPlansTheSameCells). Here the model is
  // made again at the start and may differ (a CI run: fig16's incomplete
  // object 2 was no longer modelled, 2 objects where the plan had 3), and then
  // the plan is made from the current model: not asserted to be the same.
  EXPECT_TRUE(first.contains("planned") && first["planned"].contains("contacts")) << first.dump();
  EXPECT_EQ((*s)["cleaning"]["cells_done"], done_at_stop) << s->dump();
  EXPECT_EQ((*s)["cleaning"]["cells_total"], cells_total) << s->dump();

  // kill -9 once a later cell is saved; restart; start: relocalise, clean the rest.
  const nlohmann::json second = wait_saved(done_at_stop + 1, 120);
  const int done_at_kill = CellsDone(second);
  ASSERT_GT(done_at_kill, done_at_stop);
  daemon_.Signal(SIGKILL);
  daemon_.Wait(5);
  StartDaemon();
  ASSERT_EQ(Ctl({"start", "--mode", "clean"}, &out), 0) << out;
  bool relocalised = false, clean_again = false;
  nlohmann::json last;
  const auto end = Clock::now() + std::chrono::duration<double>(WallS(150));
  while (Clock::now() < end) {
    auto st = Status();
    ASSERT_TRUE(st);
    last = *st;
    const std::string state = last["state"];
    ASSERT_NE(state, "fault") << last.dump();
    ASSERT_NE(state, "wall_follow") << "fell back to exploring: " << last.dump();
    relocalised |= state == "relocalize";
    if (state == "clean" && !clean_again) {
      clean_again = true;
      // The finished cells came back done from the saved map, none of them redone.
      EXPECT_GE(last["cleaning"]["cells_done"].get<int>(), done_at_kill) << last.dump();
      EXPECT_EQ(last["cleaning"]["cells_total"], cells_total) << last.dump();
    }
    if (state == "done") break;
    Sleep(0.25);
  }
  ASSERT_EQ(last["state"], "done") << last.dump();
  EXPECT_TRUE(relocalised);
  EXPECT_TRUE(clean_again);
  EXPECT_EQ(last["cleaning"]["cells_done"], cells_total) << last.dump();
  EXPECT_EQ(last["cleaning"]["state"], "done") << last.dump();
}

// irslam-sim run --baseline bounce: the random-bounce cleaner for the time
// fig17's planned cleaning took (275 s, docs/cleaning.md), scored against the
// truth. Deterministic for a seed: 26.1 % of 8.85 m2 (the docs' bounce column).
TEST(BounceBaselineTest, SimRunBaselineBounceReportsItsTrueCoverage) {
  const std::string dir = testing::MakeTempDir();
  std::string out;
  ASSERT_EQ(RunCommand({kBin + "/sim/irslam-sim", "run", "--world", kSrc + "/tests/worlds/fig17.json", "--baseline",
                        "bounce", "--max-time", "275", "--seed", "1", "--map-out", dir + "/bounce.json", "--svg",
                        dir + "/bounce.svg"},
                       &out, 60),
            0)
      << out;
  EXPECT_NE(out.find("irslam-sim: baseline bounce: 275.0 s robot time, covered "), std::string::npos) << out;
  const auto result = ReadJson(dir + "/bounce.json");
  ASSERT_TRUE(result);
  EXPECT_EQ((*result)["baseline"], "bounce");
  const auto& cl = (*result)["cleaning"];
  EXPECT_NEAR(cl.at("total_m2").get<double>(), 8.85, 0.05);  // fig17's reachable floor
  EXPECT_GT(cl.at("fraction").get<double>(), 0.20);
  EXPECT_LT(cl.at("fraction").get<double>(), 0.33);  // far below planned cleaning's ~90 %
  EXPECT_NEAR(cl.at("covered_m2").get<double>(), cl.at("fraction").get<double>() * cl.at("total_m2").get<double>(), 1e-9);
  EXPECT_DOUBLE_EQ(cl.at("finished_t").get<double>(), 275.0);
  // The curve grows from nothing to the final fraction.
  ASSERT_GE(cl.at("curve").size(), 28u);
  EXPECT_LT(cl.at("curve")[0][1].get<double>(), 0.05);
  EXPECT_DOUBLE_EQ(cl.at("curve").back()[1].get<double>(), cl.at("fraction").get<double>());
  EXPECT_NE(testing::ReadFile(dir + "/bounce.svg").find("<svg"), std::string::npos);
  // Without --max-time: the cleaning budget (cleaning.max_time_s).
  ASSERT_EQ(RunCommand({kBin + "/sim/irslam-sim", "run", "--world", kSrc + "/tests/worlds/fig17.json", "--baseline",
                        "bounce"},
                       &out, 60),
            0)
      << out;
  EXPECT_NE(out.find("baseline bounce: 3600.0 s robot time"), std::string::npos) << out;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace irslam
