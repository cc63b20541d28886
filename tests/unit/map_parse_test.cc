// The map back from its JSON (daemon/core_json.h MapFromJson): the exact inverse
// of ToJson(MapSnapshot) on real maps (a mission's, with faults; a cleaning
// mission's), every typed field on a synthetic one, and one clear line for
// everything malformed.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "daemon/core_json.h"
#include "daemon/map_store.h"
#include "robot/robot_core.h"
#include "sim/sim_run.h"

namespace irslam {
namespace {

using nlohmann::json;

json ReadJson(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return json::parse(ss.str());
}

// ToJson(MapFromJson(j)) == j, and the map survives the daemon's file too.
void ExpectRoundTrip(const json& j) {
  robot::MapSnapshot m;
  std::string why;
  ASSERT_TRUE(MapFromJson(j, &m, &why)) << why;
  EXPECT_EQ(ToJson(m), j);
  // Through text (as in a file): the numbers come back exactly.
  robot::MapSnapshot again;
  ASSERT_TRUE(MapFromJson(json::parse(ToJson(m).dump(1)), &again, &why)) << why;
  EXPECT_EQ(ToJson(again), j);
}

TEST(MapParseTest, TheGoldenMissionMapComesBackExactly) {
  const json j =
      ReadJson(std::string(IRSLAM_SOURCE_DIR) + "/tests/unit/testdata/core_map.golden.json");
  ExpectRoundTrip(j);
  robot::MapSnapshot m;
  std::string why;
  ASSERT_TRUE(MapFromJson(j, &m, &why)) << why;
  EXPECT_EQ(m.state, control::MissionState::kDone);
  EXPECT_EQ(m.lines.size(), j["lines"].size());
  EXPECT_EQ(m.lines[0].id, j["lines"][0]["id"].get<int>());
  EXPECT_EQ(m.lines[0].cov(0, 1), j["lines"][0]["cov"][0][1].get<double>());
  EXPECT_EQ(m.lines[0].observations, j["lines"][0]["observations"].get<int>());
  ASSERT_EQ(m.objects.size(), 3u);
  EXPECT_EQ(m.objects[1].kind, control::ObjectKind::kWallContact);
  EXPECT_EQ(m.objects[1].lines, j["objects"][1]["lines"].get<std::vector<int>>());
  EXPECT_EQ(m.objects[1].lines.size(), 3u);
  EXPECT_EQ(m.room.walls[0], (std::vector<int>{2}));
  ASSERT_TRUE(m.room.box);
  EXPECT_FALSE(m.cleaning);
  EXPECT_FALSE(m.relocalized);
  EXPECT_EQ(m.trajectory.size(), j["trajectory"].size());
}

TEST(MapParseTest, ACleaningMissionsMapComesBackExactlyWithItsCells) {
  std::string error;
  auto world =
      sim::LoadWorldFile(std::string(IRSLAM_SOURCE_DIR) + "/tests/worlds/fig14.json", &error);
  ASSERT_TRUE(world) << error;
  robot::CoreOptions o = robot::DefaultCoreOptions();
  o.mission.mode = "clean";
  o.slam.calibration.enabled = true;
  const sim::InProcessRun run = sim::RunInProcess(*world, o, 3, 2400);
  ASSERT_TRUE(run.error.empty()) << run.error;
  const robot::MapSnapshot made = run.core->Map();
  ASSERT_TRUE(made.cleaning);
  ASSERT_FALSE(made.cleaning->cells.empty());
  ASSERT_TRUE(made.calibration);
  const json j = ToJson(made);
  ExpectRoundTrip(j);
  robot::MapSnapshot m;
  ASSERT_TRUE(MapFromJson(j, &m, &error)) << error;
  ASSERT_EQ(m.cleaning->cells.size(), made.cleaning->cells.size());
  for (size_t i = 0; i < m.cleaning->cells.size(); ++i) {
    EXPECT_EQ(m.cleaning->cells[i].done, made.cleaning->cells[i].done);
    EXPECT_EQ(m.cleaning->cells[i].polygon, made.cleaning->cells[i].polygon);
  }
  EXPECT_EQ(m.calibration->value.base, made.calibration->value.base);
  // And through the daemon's map file.
  const auto stored = DecodeMapFile(EncodeMapFile({1, "stop", j}), &error);
  ASSERT_TRUE(stored) << error;
  ExpectRoundTrip(stored->map);
}

robot::MapSnapshot SyntheticMap() {
  robot::MapSnapshot m;
  m.state = control::MissionState::kDone;
  m.pose = {1.25, -0.5, 0.75};
  m.pose_cov << 1e-4, 2e-5, 0, 2e-5, 3e-4, 1e-6, 0, 1e-6, 5e-5;
  for (int id : {1, 2, 3, 4, 7}) {
    slam::LineFeature l;
    l.id = id;
    l.rho = 0.1 * id;
    l.theta = id % 2 ? M_PI / 2 : 0.0;
    l.cov << 1e-4, 1e-5, 1e-5, 2e-3;
    l.p0 = {0.1 * id, 0.2};
    l.p1 = {0.3 * id, 1.7};
    l.observations = 3 * id;
    if (id == 3) l.merged = {9, 11};  // saved pieces of its wall merged into it
    m.lines.push_back(l);
  }
  m.room.walls = {std::vector<int>{1}, {2}, {3}, {4}};
  m.room.box = control::Box{-0.1, -0.2, 3.9, 5.4};
  control::ObjectModel o;
  o.id = 5;
  o.kind = control::ObjectKind::kFree;
  o.lines = {7};
  o.box = {1, 1, 2, 2.5};
  o.open_ends = 2;
  o.note = "moved: sides no longer where they were";
  m.objects = {o};
  m.trajectory = {{0.25, {0, 0, 0}}, {0.5, {0.01, 0, 0.02}}};
  control::CleaningProgress c;
  c.state = control::CleanState::kDone;
  c.started_t = 100;
  c.finished_t = 400.5;
  c.cells_done = 1;
  c.cells_total = 2;
  c.covered_m2 = 3.5;
  c.total_m2 = 4;
  c.fraction = 0.875;
  c.path_m = 60;
  c.cleaning_width_m = 0.3;
  c.cells = {{1, {{0, 0}, {1, 0}, {1, 1}}, {{0.1, 0.1}, {0.9, 0.1}}, true, false},
             {2, {{1, 0}, {2, 0}, {2, 1}}, {}, false, true}};
  c.planned = control::CleaningProgress::PlanInputs{{-0.1, -0.2, 3.9, 5.4}, {{1, 1, 2, 2.5}}, {{0.5, 0.25}}};
  m.cleaning = c;
  m.calibration =
      slam::CalibrationEstimate{{1.0043, 0.9941, 1.0178}, Eigen::Vector3d(4e-3, 4e-3, 2e-3), 3e-4};
  m.relocalized = robot::MapSnapshot::Relocalized{31.5, 2};
  return m;
}

TEST(MapParseTest, EveryTypedFieldComesBack) {
  const robot::MapSnapshot m = SyntheticMap();
  const json j = ToJson(m);
  EXPECT_EQ(j["relocalized"].dump(), R"({"hypotheses":2,"t":31.5})");
  ExpectRoundTrip(j);
  robot::MapSnapshot back;
  std::string why;
  ASSERT_TRUE(MapFromJson(j, &back, &why)) << why;
  EXPECT_EQ(back.pose_cov, m.pose_cov);
  EXPECT_EQ(back.objects[0].note, m.objects[0].note);
  EXPECT_EQ(back.objects[0].open_ends, 2);
  EXPECT_EQ(back.lines[2].merged, (std::vector<int>{9, 11}));
  EXPECT_EQ(j["lines"][2]["merged"].dump(), "[9,11]");
  EXPECT_FALSE(j["lines"][0].contains("merged"));  // only where there are some
  EXPECT_EQ(back.cleaning->cells[1].unreachable, true);
  EXPECT_EQ(back.cleaning->cells[0].route, m.cleaning->cells[0].route);
  EXPECT_EQ(back.cleaning->finished_t, 400.5);
  EXPECT_EQ(back.cleaning->swept_t, 0);  // written as null
  ASSERT_TRUE(back.cleaning->planned);
  EXPECT_EQ(j["cleaning"]["planned"].dump(),
            R"({"contacts":[[0.5,0.25]],"objects":[[1.0,1.0,2.0,2.5]],"room":[-0.1,-0.2,3.9,5.4]})");
  EXPECT_EQ(back.cleaning->planned->contacts, m.cleaning->planned->contacts);
  EXPECT_EQ(back.cleaning->planned->objects[0].ymax, 2.5);
  EXPECT_EQ(back.cleaning->planned->room.xmin, -0.1);
  EXPECT_EQ(back.calibration->ratio_sigma, 3e-4);
  ASSERT_TRUE(back.relocalized);
  EXPECT_EQ(back.relocalized->t, 31.5);
  EXPECT_EQ(back.relocalized->hypotheses, 2);
  // Unknown keys (the API's "saved") are allowed; a map without the optional parts too.
  json served = j;
  served["saved"] = {{"seq", 3}, {"reason", "stop"}, {"path", "/var/lib/irslam/map.json"}};
  EXPECT_TRUE(MapFromJson(served, &back, &why)) << why;
  EXPECT_TRUE(MapFromJson(json{{"frame", "map"},
                               {"state", "idle"},
                               {"lines", json::array()},
                               {"objects", json::array()}},
                          &back, &why))
      << why;
  EXPECT_TRUE(back.lines.empty());
  EXPECT_FALSE(back.room.box);
  // Side ids that name no line (lines merged after the model was made) are kept.
  json stale = j;
  stale["objects"][0]["lines"].push_back(99);
  stale["room"]["walls"]["left"].push_back(98);
  ASSERT_TRUE(MapFromJson(stale, &back, &why)) << why;
  EXPECT_EQ(back.objects[0].lines, (std::vector<int>{7, 99}));
  EXPECT_EQ(ToJson(back), stale);
}

// A status without relocalisation has no "relocalize" key; with it, the
// numbers (the commit time null before the commit).
TEST(MapParseTest, TheStatusShowsRelocalisationOnlyWhenThereIsSome) {
  robot::CoreStatus s;
  EXPECT_FALSE(ToJson(s).contains("relocalize"));
  s.relocalize = robot::RelocalizeStatus{false, 2.5, 0, 4, 0.25, 1.5, 1};
  EXPECT_EQ(
      ToJson(s)["relocalize"].dump(),
      R"({"attempts":1,"best_score":0.25,"committed":false,"committed_t":null,"evidence_m":1.5,)"
      R"("hypotheses":4,"started_t":2.5})");
  s.relocalize->committed = true;
  s.relocalize->committed_t = 20.5;
  s.relocalize->best_score = -std::numeric_limits<double>::infinity();
  EXPECT_EQ(ToJson(s)["relocalize"]["committed_t"].dump(), "20.5");
  EXPECT_TRUE(ToJson(s)["relocalize"]["best_score"].is_null());
  EXPECT_FALSE(ToJson(robot::MapSnapshot())["relocalized"].is_object());
  EXPECT_FALSE(ToJson(robot::MapSnapshot()).contains("relocalized"));
}

struct BadMap {
  const char* pointer;  // JSON pointer of the value replaced
  json value;           // the replacement (discarded: the key removed)
  const char* error;
};

TEST(MapParseTest, EachMalformedFieldIsOneClearLine) {
  const json good = ToJson(SyntheticMap());
  const double inf = std::numeric_limits<double>::infinity();
  const BadMap cases[] = {
      {"/frame", "world", "map.frame: not \"map\""},
      {"/state", "flying", "map.state: unknown value \"flying\""},
      {"/state", json::value_t::discarded, "map.state: missing"},
      {"/pose", {1, 2}, "map.pose: not an array of 3 numbers"},
      {"/pose/2", "x", "map.pose[2]: not a number"},
      {"/pose/0", inf, "map.pose[0]: not a finite number within ±1000"},
      {"/pose/1", 1e7, "map.pose[1]: not a finite number within ±1000"},
      {"/pose_cov/1", {1, 2}, "map.pose_cov: not a 3x3 matrix of numbers"},
      {"/lines", 5, "map.lines: not an array"},
      {"/lines/0", 5, "map.lines[0]: not an object"},
      {"/lines/1/id", 2.5, "map.lines[1].id: not an integer"},
      {"/lines/1/id", -3, "map.lines[1].id: out of range [0, 2147483647]"},
      {"/lines/1/id", 18446744073709551615u, "map.lines[1].id: out of range [0, 2147483647]"},
      {"/lines/1/id", 1, "map.lines[1].id: line 1 is in the map twice"},
      {"/lines/2/rho", json::value_t::discarded, "map.lines[2].rho: missing"},
      {"/lines/2/cov/0/1", "a", "map.lines[2].cov[0][1]: not a number"},
      {"/lines/2/cov", {{1, 2}}, "map.lines[2].cov: not a 2x2 matrix of numbers"},
      {"/lines/3/p1", {1, 2, 3}, "map.lines[3].p1: not an array of 2 numbers"},
      {"/lines/2/merged/1", "x", "map.lines[2].merged[1]: not an integer"},
      {"/lines/2/merged", 9, "map.lines[2].merged: not an array"},
      {"/room/walls/left", {-99}, "map.room.walls.left[0]: out of range [0, 2147483647]"},
      {"/room/walls/middle", {1}, "map.room.walls.middle: not bottom, right, top or left"},
      {"/room/box", {1, 2, 3}, "map.room.box: not an array of 4 numbers"},
      {"/objects/0/lines/0", "7", "map.objects[0].lines[0]: not an integer"},
      {"/objects/1",
       {{"id", 5}, {"kind", "free"}, {"lines", json::array()}},
       "map.objects[1].id: object 5 is in the map twice"},
      {"/objects/0/kind", "sofa", "map.objects[0].kind: not \"wall_contact\" or \"free\""},
      {"/objects/0/complete", 1, "map.objects[0].complete: not a boolean"},
      {"/objects/0/note", 7, "map.objects[0].note: not a string"},
      {"/trajectory/1", {1, 2, 3}, "map.trajectory[1]: not an array of 4 numbers"},
      {"/cleaning/state", "mopping", "map.cleaning.state: unknown value \"mopping\""},
      {"/cleaning/cells/0/done", "yes", "map.cleaning.cells[0].done: not a boolean"},
      {"/cleaning/cells/1/polygon/0",
       {1},
       "map.cleaning.cells[1].polygon[0]: not an array of 2 numbers"},
      {"/cleaning/finished_t", "late", "map.cleaning.finished_t: not a number"},
      {"/cleaning/planned", 3, "map.cleaning.planned: not an object"},
      {"/cleaning/planned/room", json::value_t::discarded, "map.cleaning.planned.room: missing"},
      {"/cleaning/planned/objects/0", {1, 2}, "map.cleaning.planned.objects[0]: not an array of 4 numbers"},
      {"/cleaning/planned/contacts/0/1", "x", "map.cleaning.planned.contacts[0][1]: not a number"},
      {"/calibration/scale/0", 3.0, "map.calibration.scale: a scale factor outside [0.5, 1.5]"},
      {"/calibration/std", {1, 2}, "map.calibration.std: not an array of 3 numbers"},
      {"/relocalized/hypotheses", -1, "map.relocalized.hypotheses: out of range [0, 2147483647]"},
      {"/relocalized/t", json::value_t::discarded, "map.relocalized.t: missing"},
  };
  for (const BadMap& c : cases) {
    json bad = good;
    const json::json_pointer ptr(c.pointer);
    if (c.value.is_discarded()) {
      bad[ptr.parent_pointer()].erase(ptr.back());
    } else {
      bad[ptr] = c.value;
    }
    robot::MapSnapshot m;
    std::string why;
    EXPECT_FALSE(MapFromJson(bad, &m, &why)) << c.pointer;
    EXPECT_EQ(why, c.error) << c.pointer;
  }
  robot::MapSnapshot m;
  std::string why;
  EXPECT_FALSE(MapFromJson(json::array(), &m, &why));
  EXPECT_EQ(why, "map: not an object");
  // Absurd sizes are refused before anything is built from them.
  json huge = good;
  huge["lines"] = json::array();
  for (size_t i = 0; i <= kMaxMapLines; ++i) huge["lines"].push_back(good["lines"][0]);
  EXPECT_FALSE(MapFromJson(huge, &m, &why));
  EXPECT_EQ(why, "map.lines: more than 10000 entries");
}

}  // namespace
}  // namespace irslam
