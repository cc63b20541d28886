#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include "daemon/access.h"
#include "daemon/config.h"
#include "io/json_text.h"
#include "tests/testing/process.h"

namespace irslam {
namespace {

TEST(ConfigTest, ShippedFileEqualsTheBuiltInDefaults) {
  DaemonSettings o;
  std::string error;
  ASSERT_TRUE(LoadConfigFile(IRSLAM_SOURCE_DIR "/daemon/irslamd.conf", &o, &error)) << error;
  // Sensor mounts and Hough angles in the file are rounded to 1e-7.
  const DaemonSettings d;
  EXPECT_NEAR(o.core.slam.extraction.hough_theta_res_rad, d.core.slam.extraction.hough_theta_res_rad, 1e-7);
  EXPECT_NEAR(o.core.slam.extraction.hough_theta_window_rad, d.core.slam.extraction.hough_theta_window_rad, 1e-7);
  o.core.slam.extraction.hough_theta_res_rad = d.core.slam.extraction.hough_theta_res_rad;
  o.core.slam.extraction.hough_theta_window_rad = d.core.slam.extraction.hough_theta_window_rad;
  for (int i = 0; i < kNumIrSensors; ++i) {
    EXPECT_NEAR(o.core.slam.mounts[i].theta, d.core.slam.mounts[i].theta, 1e-6);
    EXPECT_NEAR(o.core.slam.mounts[i].x, d.core.slam.mounts[i].x, 1e-6);
    o.core.slam.mounts[i] = d.core.slam.mounts[i];
  }
  EXPECT_EQ(DumpConfig(o), DumpConfig(d));
}

// Every parameter is documented in the shipped file, from one source: the file
// is what the option tables generate for the defaults (regenerate it with
// `build/daemon/irslamd --print-default-config > daemon/irslamd.conf`).
TEST(ConfigTest, ShippedFileIsGeneratedFromTheOptionTables) {
  EXPECT_EQ(testing::ReadFile(IRSLAM_SOURCE_DIR "/daemon/irslamd.conf"),
            DocumentedConfig(DaemonSettings()))
      << "daemon/irslamd.conf is not what the option tables say: regenerate it";
}

// Every key the daemon prints (--print-config) is in the generated file too.
TEST(ConfigTest, GeneratedFileListsEveryParameter) {
  std::string error;
  const auto shipped = ParseJsonText(DocumentedConfig(DaemonSettings()), &error);
  ASSERT_TRUE(shipped) << error;
  const auto all = ParseJsonText(DumpConfig(DaemonSettings()), &error);
  ASSERT_TRUE(all) << error;
  const nlohmann::json flat_shipped = shipped->flatten(), flat_all = all->flatten();
  EXPECT_EQ(flat_shipped.size(), flat_all.size());
  for (const auto& [key, value] : flat_all.items()) {
    EXPECT_TRUE(flat_shipped.contains(key)) << key;
  }
}

TEST(ConfigTest, OverridesOnlyWhatIsGiven) {
  DaemonSettings o;
  std::string error;
  ASSERT_TRUE(ParseConfig(R"({ // comment
      "wall_follow": {"follow_distance_m": 0.5}, "control": {"period_s": 0.01}})", &o, &error))
      << error;
  EXPECT_DOUBLE_EQ(o.core.wall.follow_distance_m, 0.5);
  EXPECT_DOUBLE_EQ(o.core.period_s, 0.01);
  EXPECT_DOUBLE_EQ(o.core.wall.cruise_speed_mps, robot::DefaultCoreOptions().wall.cruise_speed_mps);
}

TEST(ConfigTest, RejectsUnknownKeysByFullName) {
  DaemonSettings o;
  std::string error;
  EXPECT_FALSE(ParseConfig(R"({"wall_follow": {"follow_distanse_m": 0.5}})", &o, &error));
  EXPECT_EQ(error, "config: wall_follow.follow_distanse_m is not a known key");
  EXPECT_FALSE(ParseConfig(R"({"walls": {}})", &o, &error));
  EXPECT_EQ(error, "config: walls is not a known key");
}

// fuzz_world found it (2026-12-02), the config echoed keys the same way: a key
// with an escaped newline came back as a two-line error.
TEST(ConfigTest, AnUnknownKeyWithAControlCharacterIsStillOneLine) {
  DaemonSettings o;
  std::string error;
  EXPECT_FALSE(ParseConfig(R"({"a\nb": 1})", &o, &error));
  EXPECT_EQ(error, R"(config: a\nb is not a known key)");
  EXPECT_FALSE(ParseConfig(R"({"api": {"x\u0001": 1}})", &o, &error));
  EXPECT_EQ(error, R"(config: api.x\u0001 is not a known key)");
  EXPECT_FALSE(ParseConfig(R"({"gpio": {"estop": {"chip": "c", "line": 0, "l\ri": 1}}})", &o, &error));
  EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  EXPECT_EQ(error.find('\r'), std::string::npos) << error;
}

TEST(ConfigTest, RejectsBadValuesWithOneLineNamingTheKey) {
  const std::pair<const char*, const char*> cases[] = {
      {R"({"control": {"period_s": "fast"}})", "config: control.period_s must be a number"},
      {R"({"control": {"period_s": 5}})", "config: control.period_s must be in [0.001, 1] (got 5)"},
      {R"({"robot": 3})", "config: robot must be an object"},
      {R"({"sensors": {"mounts": [[0,0,0]]}})", "config: sensors.mounts must list exactly 7"},
      {R"({"sensors": {"table": [[0.1, 1.0], [0.2, 2.0]]}})", "config: sensors.table must have"},
      {R"({"sensors": {"adc_bits": 12.5}})", "config: sensors.adc_bits must be an integer"},
      {"{\"robot\": {", "config: not valid JSON"},
      {"[]", "config: the top level must be an object"},
      {R"({"control": {"period_s": 1e999}})", "config: not valid JSON: number overflow"},
  };
  for (const auto& [text, want] : cases) {
    DaemonSettings o;
    const std::string before = DumpConfig(o);
    std::string error;
    EXPECT_FALSE(ParseConfig(text, &o, &error)) << text;
    EXPECT_EQ(error.rfind(want, 0), 0u) << text << " -> " << error;
    EXPECT_EQ(error.find('\n'), std::string::npos);
    EXPECT_EQ(DumpConfig(o), before) << "a rejected config must change nothing";
  }
}

TEST(ConfigTest, MissingFileIsOneLine) {
  DaemonSettings o;
  std::string error;
  EXPECT_FALSE(LoadConfigFile("/nonexistent/irslamd.conf", &o, &error));
  EXPECT_EQ(error, "config: cannot read /nonexistent/irslamd.conf: No such file or directory");
}

// Issue 12: a FIFO as config hung start-up (and SIGHUP hung the loop); /dev/zero
// aborted with bad_alloc; a file nested 150,000 levels deep crashed the parser.
TEST(ConfigTest, AFifoOrDeviceIsRefusedAtOnce) {
  const std::string dir = ::testing::TempDir() + "/config-fifo-" + std::to_string(::getpid());
  ::mkdir(dir.c_str(), 0700);
  const std::string fifo = dir + "/irslamd.conf";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  DaemonSettings o;
  std::string error;
  EXPECT_FALSE(LoadConfigFile(fifo, &o, &error));
  EXPECT_EQ(error, "config: cannot read " + fifo + ": not a regular file");
  EXPECT_FALSE(LoadConfigFile("/dev/zero", &o, &error));
  EXPECT_EQ(error, "config: cannot read /dev/zero: not a regular file");
  ::unlink(fifo.c_str());
  ::rmdir(dir.c_str());
}

TEST(ConfigTest, DeepNestingIsOneLineNotACrash) {
  DaemonSettings o;
  std::string error;
  const std::string deep = "{\"slam\": " + std::string(150000, '[') + std::string(150000, ']') + "}";
  EXPECT_FALSE(ParseConfig(deep, &o, &error));
  EXPECT_EQ(error, "config: nested deeper than 64 levels");
}

}  // namespace
}  // namespace irslam

namespace irslam {
namespace {

TEST(AccessTest, RootAndTheDaemonsUserMayDoEverything) {
  AccessPolicy p{1000, 50, 60};
  EXPECT_TRUE(Allowed(p, 0, {}, Access::kControl));
  EXPECT_TRUE(Allowed(p, 1000, {}, Access::kControl));
}

TEST(AccessTest, ReadAndControlGroups) {
  AccessPolicy p{1000, 50, 60};
  EXPECT_TRUE(Allowed(p, 2000, {7, 50}, Access::kRead));
  EXPECT_FALSE(Allowed(p, 2000, {7, 50}, Access::kControl));
  EXPECT_TRUE(Allowed(p, 2001, {60}, Access::kControl));
  EXPECT_TRUE(Allowed(p, 2001, {60}, Access::kRead));  // control implies read
  EXPECT_FALSE(Allowed(p, 2002, {7}, Access::kRead));
}

TEST(AccessTest, UnsetGroupsLeaveItToTheSocketsPermissions) {
  AccessPolicy p{1000, std::nullopt, std::nullopt};
  EXPECT_TRUE(Allowed(p, 2002, {7}, Access::kRead));
  EXPECT_TRUE(Allowed(p, 2002, {7}, Access::kControl));
  p.control_gid = 60;
  EXPECT_TRUE(Allowed(p, 2002, {7}, Access::kRead));
  EXPECT_FALSE(Allowed(p, 2002, {7}, Access::kControl));
}

TEST(AccessTest, PeerGroupsIncludeThePrimaryAndSupplementaryGroups) {
  const auto g = PeerGroups(0, 0);
  ASSERT_FALSE(g.empty());
  EXPECT_EQ(g.front(), 0u);
  std::string error;
  EXPECT_EQ(GroupId("root", &error), std::optional<gid_t>(0));
  EXPECT_FALSE(GroupId("no-such-group-irslam", &error));
  EXPECT_EQ(error, "api: no such group 'no-such-group-irslam'");
}

}  // namespace
}  // namespace irslam

namespace irslam {
namespace {

// SIGHUP keeps the GPIO lines opened at start: only a change of lines needs a
// restart; a new debounce time applies at once.
TEST(ConfigTest, GpioLinesCompareWithoutTheDebounceTime) {
  DaemonSettings a, b;
  a.gpio.estop = {"gpio-sim-robot", "estop", true};
  b = a;
  b.core.safety.debounce_s = 0.05;
  EXPECT_TRUE(a.gpio.SameLines(b.gpio));
  b.gpio.estop.active_low = false;
  EXPECT_FALSE(a.gpio.SameLines(b.gpio));
  b = a;
  b.gpio.status_led.chip = "gpiochip0";
  EXPECT_FALSE(a.gpio.SameLines(b.gpio));
}

// [gpio] is split: the lines are the daemon's, debounce_s the core's.
TEST(ConfigTest, GpioSectionSetsTheDaemonsLinesAndTheCoresDebounce) {
  DaemonSettings o;
  std::string error;
  ASSERT_TRUE(ParseConfig(R"({"gpio": {"estop": {"chip": "gpiochip0", "line": 3}, "debounce_s": 0.05},
      "state": {"dir": "/tmp/x"}, "api": {"max_clients": 3}, "record": {"files": 2}})", &o, &error))
      << error;
  EXPECT_EQ(o.gpio.estop.chip, "gpiochip0");
  EXPECT_EQ(o.gpio.estop.line, "3");
  EXPECT_DOUBLE_EQ(o.core.safety.debounce_s, 0.05);
  EXPECT_EQ(o.state_dir, "/tmp/x");
  EXPECT_EQ(o.api.max_clients, 3);
  EXPECT_EQ(o.record.files, 2);
}

}  // namespace
}  // namespace irslam
