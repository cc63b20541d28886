// The candump -L log format, the offline replay (daemon/replay.h) and irslamd's bus
// recorder (daemon/bus_recorder.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>

#include "daemon/bus_recorder.h"
#include "daemon/candump_log.h"
#include "daemon/core_json.h"
#include "daemon/replay.h"
#include "proto/codec.h"
#include "sim/sim_run.h"
#include "tests/testing/process.h"
#include "tests/testing/worlds.h"

namespace irslam {
namespace {

LogLine Parse(std::string_view text) {
  LogLine l;
  std::string error;
  EXPECT_TRUE(ParseLogLine(text, &l, &error)) << text << ": " << error;
  return l;
}

std::string ParseError(std::string_view text) {
  LogLine l;
  std::string error;
  EXPECT_FALSE(ParseLogLine(text, &l, &error)) << text;
  return error;
}

TEST(CandumpLogTest, ParsesCanUtilsLines) {
  const LogLine l = Parse("(1700000000.123456) vcan0 110#0102030405060708");
  EXPECT_EQ(l.kind, LogLine::Kind::kFrame);
  EXPECT_EQ(l.stamp_ns, 1700000000123456000);
  EXPECT_EQ(l.iface, "vcan0");
  EXPECT_EQ(l.frame.can_id, 0x110u);
  EXPECT_EQ(l.frame.can_dlc, 8);
  EXPECT_EQ(l.frame.data[7], 0x08);
  // candump -x's direction flag, a CR line end, an empty frame, nanoseconds.
  EXPECT_EQ(Parse("(1700000000.123456) can0 080#00 T\r").frame.can_dlc, 1);
  EXPECT_EQ(Parse("(0000000001.000000) loopback 0A0#").frame.can_dlc, 0);
  EXPECT_EQ(Parse("(1.000000001) can0 0A0#0000").stamp_ns, 1000000001);
}

TEST(CandumpLogTest, ForeignFramesCommentsAndBlanksAreNotFrames) {
  EXPECT_EQ(Parse("(1700000000.123456) can0 12345678#DEAD").kind, LogLine::Kind::kForeign);
  EXPECT_EQ(Parse("(1700000000.123456) can0 123##1DEADBEEF").kind, LogLine::Kind::kForeign);
  EXPECT_EQ(Parse("(1700000000.123456) can0 123#R").kind, LogLine::Kind::kForeign);
  EXPECT_EQ(Parse("# a note").kind, LogLine::Kind::kComment);
  EXPECT_EQ(Parse("").kind, LogLine::Kind::kBlank);
  EXPECT_EQ(Parse("   ").kind, LogLine::Kind::kBlank);
}

TEST(CandumpLogTest, MalformedLinesSayWhatIsWrong) {
  EXPECT_EQ(ParseError("1700000000.123456 can0 110#00"), "bad time stamp (want \"(SECONDS.MICROS)\")");
  EXPECT_EQ(ParseError("(1700000000.1234567890) can0 110#00"), "bad time stamp (want \"(SECONDS.MICROS)\")");
  EXPECT_EQ(ParseError("(1700000000.123456) can0"), "truncated line (want \"(STAMP) IFACE ID#DATA\")");
  EXPECT_EQ(ParseError("(1700000000.123456) can0 110#0102030"), "bad frame data (want up to 8 bytes in hex)");
  EXPECT_EQ(ParseError("(1700000000.123456) can0 110#010203040506070809"),
            "bad frame data (want up to 8 bytes in hex)");
  EXPECT_EQ(ParseError("(1700000000.123456) can0 1100#00"), "bad frame id (want 3 or 8 hex digits)");
  EXPECT_EQ(ParseError("(1700000000.123456) can0 11G#00"), "bad frame (want ID#DATA in hex)");
  EXPECT_EQ(ParseError("(1700000000.123456) can0 110#00 X"), "unexpected text after the frame");
  EXPECT_EQ(ParseError(std::string(600, 'x')), "line longer than 512 bytes");
}

TEST(CandumpLogTest, FormatsWhatItParses) {
  can_frame f{};
  f.can_id = 0x121;
  f.can_dlc = 3;
  f.data[0] = 0xAB;
  const std::string line = FormatLogLine(1700000000123456789, "vcan0", f);
  EXPECT_EQ(line, "(1700000000.123456) vcan0 121#AB0000");
  const LogLine back = Parse(line);
  EXPECT_EQ(back.stamp_ns, 1700000000123456000);
  EXPECT_EQ(back.frame.can_id, 0x121u);
  EXPECT_EQ(back.frame.can_dlc, 3);
}

TEST(CandumpLogTest, RecordHeaderRoundTrips) {
  const RecordHeader h{1700000000123456789, 10, 0.02};
  const std::string text = FormatRecordHeader(h);
  EXPECT_EQ(text, "# irslamd-record v1 origin=1700000000.123456789 time_scale=10 period_s=0.02");
  const auto back = ParseRecordHeader(text);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->origin_ns, h.origin_ns);
  EXPECT_EQ(back->time_scale, 10);
  EXPECT_EQ(back->period_s, 0.02);
  EXPECT_FALSE(ParseRecordHeader("# a note"));
  EXPECT_FALSE(ParseRecordHeader("# irslamd-record v1 origin=1.5 time_scale=0 period_s=0.02"));
}

TEST(CandumpLogTest, EventCommentsRoundTrip) {
  const std::string text = FormatEventComment(1700000000123456000, "start");
  EXPECT_EQ(text, "# irslamd-event (1700000000.123456) start");
  const auto e = ParseEventComment(text);
  ASSERT_TRUE(e);
  EXPECT_EQ(e->stamp_ns, 1700000000123456000);
  EXPECT_EQ(e->name, "start");
  EXPECT_EQ(Parse(text).kind, LogLine::Kind::kComment);
  EXPECT_FALSE(ParseEventComment("# irslamd-event (17000.1) start extra"));
  EXPECT_FALSE(ParseEventComment("# irslamd-event start"));
}

TEST(ReplayTest, EstimatesTheTimeScaleFromTheCommandSpacing) {
  std::vector<int64_t> stamps;
  // 2 ms at 10x with up to 0.3 ms of wake-up jitter, and one skipped period.
  for (int i = 0; i < 60; ++i) stamps.push_back(1000000000 + (i + (i > 40)) * 2000000 + (i % 3) * 300000);
  EXPECT_EQ(EstimateTimeScale(stamps, 0.02), 10.0);
  stamps.clear();
  for (int i = 0; i < 60; ++i) stamps.push_back(i * 8000000);  // 2.5x: two digits
  EXPECT_EQ(EstimateTimeScale(stamps, 0.02), 2.5);
  stamps.clear();
  for (int i = 0; i < 50; ++i) stamps.push_back(i * 20000000);
  EXPECT_EQ(EstimateTimeScale(stamps, 0.02), 1.0);
  EXPECT_FALSE(EstimateTimeScale({1, 2, 3}, 0.02));
}

TEST(ReplayTest, EstimatesTheTimeScaleOfALoadedMachineThatSkipsPeriods) {
  // CI's failure (stop 24): at 10x a loaded machine skipped a period in ~1 of 6 ticks,
  // every window of 10 held a skip, and the median window said 9x. Here: a skip every
  // 6th tick, 0-0.8 ms of wake-up latency on the absolute 2 ms clock.
  std::vector<int64_t> stamps;
  int64_t period = 0;
  for (int i = 0; i < 3000; ++i) {
    period += (i % 6 == 5) ? 2 : 1;
    stamps.push_back(1000000000 + period * 2000000 + (i * 7919 % 9) * 100000);
  }
  EXPECT_EQ(EstimateTimeScale(stamps, 0.02), 10.0);
  // 2 in 5 ticks skip a period (0-0.4 ms of latency): still 10x.
  stamps.clear();
  period = 0;
  for (int i = 0; i < 3000; ++i) {
    period += 1 + (i * 7919 % 5 < 2);
    stamps.push_back(period * 2000000 + (i * 104729 % 5) * 100000);
  }
  EXPECT_EQ(EstimateTimeScale(stamps, 0.02), 10.0);
}

TEST(ReplayTest, TellsTheTimeScaleFromTheControllersEncoderStamps) {
  // 10x on a loaded machine: a 100 Hz controller (10 ms robot, 1 ms wall) whose frames
  // arrive in bursts: every 37th wake-up the bystander is starved for 0-60 ms and then
  // receives what queued, all stamped at once. 60 s of robot time.
  ControllerClockFit fit;
  int64_t starved_until_ns = 0;
  for (int i = 0; i < 6000; ++i) {
    const int64_t sent_ns = 5'000'000'000 + int64_t{i} * 1'000'000;
    if (i % 37 == 0) starved_until_ns = sent_ns + (i * 7919 % 61) * 1'000'000;
    const int64_t received_ns = std::max(sent_ns + 50'000, starved_until_ns);
    fit.Add(received_ns, static_cast<uint16_t>((1234 + i * 10) & 0xFFFF));
  }
  EXPECT_EQ(fit.frames(), 6000u);
  EXPECT_EQ(fit.Scale(), 10.0);
}

TEST(ReplayTest, TheEncoderClockFitUnwrapsTheStampAndSurvivesAResetAndReordering) {
  // 1x for 200 s: the 16-bit millisecond stamp wraps three times. Halfway the
  // controller restarts (its stamp back to 0), and two frames arrive swapped.
  ControllerClockFit fit;
  uint16_t stamp = 65000;
  std::vector<std::pair<int64_t, uint16_t>> frames;
  for (int i = 0; i < 20000; ++i) {
    if (i == 10000) stamp = 0;
    frames.emplace_back(int64_t{i} * 10'000'000 + (i % 5) * 200'000, stamp);
    stamp = static_cast<uint16_t>(stamp + 10);
  }
  std::swap(frames[15000], frames[15001]);
  for (const auto& [ns, ms] : frames) fit.Add(ns, ms);
  EXPECT_EQ(fit.Scale(), 1.0);
  // 2.5x: two significant digits.
  ControllerClockFit fit25;
  for (int i = 0; i < 1000; ++i) fit25.Add(int64_t{i} * 4'000'000, static_cast<uint16_t>(i * 10));
  EXPECT_EQ(fit25.Scale(), 2.5);
  // Too little: under 100 frames, or under 1 s of robot time.
  ControllerClockFit few;
  for (int i = 0; i < 99; ++i) few.Add(int64_t{i} * 10'000'000, static_cast<uint16_t>(i * 10));
  EXPECT_FALSE(few.Scale());
  ControllerClockFit short_span;
  for (int i = 0; i < 500; ++i) short_span.Add(int64_t{i} * 100'000, static_cast<uint16_t>(i / 10));
  EXPECT_FALSE(short_span.Scale());
}

// A mission in process (the same exchange as sim/sim_run.cc), every frame written
// as a candump -L line at its time, as irslamd's recorder does; optionally stopped
// by a `stop` call (and its stop frame) at stop_at_s.
struct Recorded {
  std::vector<std::string> lines;
  robot::MapSnapshot map;
  uint64_t ticks = 0;
};

// notes: the start and stop calls noted as irslamd's recorder does (event comments).
Recorded RecordMission(const std::string& world, double max_time_s, double stop_at_s = 1e9, bool notes = false) {
  const robot::CoreOptions options = robot::DefaultCoreOptions();
  sim::SimController sim(testing::LoadTestWorld(world), sim::SimOptionsFrom(options), 3);
  robot::RobotCore core(options);
  Recorded rec;
  const int64_t origin = 1700000000000000000;
  // Time in whole microseconds, as irslamd's (Daemon::RobotNow): the log holds it exactly.
  int64_t ns = 0;
  const auto log = [&](const can_frame& f) { rec.lines.push_back(FormatLogLine(origin + ns, "vcan0", f)); };
  rec.lines.push_back(FormatRecordHeader({origin, 1, options.period_s}));
  double next_tick = options.period_s;
  bool started = false, stopped = false;
  std::vector<can_frame> frames;
  for (double t = 0; t < max_time_s;) {
    ns += 2000000;
    t = RobotTimeFromLogNs(ns, 1.0);
    frames.clear();
    sim.AdvanceTo(t, &frames);
    for (const can_frame& f : frames) {
      log(f);
      core.OnFrame(f, t);
    }
    if (!stopped && t >= stop_at_s) {
      core.Stop(t);
      if (notes) rec.lines.push_back(FormatEventComment(origin + ns, "stop"));
      const can_frame stop = core.StopFrame();
      log(stop);
      sim.HandleFrame(stop);
      stopped = true;
    }
    if (t < next_tick - 1e-9) continue;
    next_tick += options.period_s;
    if (!started && t > 0.3) {
      std::string why;
      EXPECT_TRUE(core.Start(t, &why)) << why;
      if (notes) rec.lines.push_back(FormatEventComment(origin + ns, "start"));
      started = true;
    }
    ++rec.ticks;
    for (const can_frame& f : core.Tick(t)) {
      log(f);
      sim.HandleFrame(f);
    }
    if (started && core.state() == control::MissionState::kDone) break;
  }
  rec.map = core.Map();
  return rec;
}

// noted: as irslam-replay does for irslamd's recordings (start and stop are noted).
ReplayStats ReplayLines(const std::vector<std::string>& lines, robot::MapSnapshot* map, bool noted = false) {
  std::optional<RecordHeader> header;
  std::unique_ptr<Replay> replay;
  for (const std::string& text : lines) {
    const LogLine l = Parse(text);
    if (l.kind == LogLine::Kind::kComment) {
      if (!header) header = ParseRecordHeader(text);
      if (const auto event = ParseEventComment(text); event && replay) replay->OnEvent(*event);
    }
    if (l.kind != LogLine::Kind::kFrame) continue;
    if (!replay) {
      EXPECT_TRUE(header);
      replay = std::make_unique<Replay>(robot::DefaultCoreOptions(), header->origin_ns, header->time_scale);
      if (noted) replay->SetNoted();
    }
    replay->Feed(l);
  }
  *map = replay->core().Map();
  return replay->stats();
}

TEST(ReplayTest, ARecordedMissionReplaysToTheSameMapBitForBit) {
  const Recorded rec = RecordMission("wall_follow_fig14", 200);
  ASSERT_EQ(rec.map.state, control::MissionState::kDone);
  robot::MapSnapshot map;
  const ReplayStats s = ReplayLines(rec.lines, &map);
  EXPECT_EQ(s.ticks, rec.ticks);
  EXPECT_EQ(s.starts, 1u);
  EXPECT_EQ(s.stops, 0u);
  EXPECT_EQ(s.commands_differed, 0u);
  EXPECT_GT(s.commands_matched, 2000u);
  EXPECT_EQ(s.states_differed, 0u);
  EXPECT_EQ(map.state, control::MissionState::kDone);
  // The JSON views, number for number (the map file of contracts §4).
  const nlohmann::json live = ToJson(rec.map), replayed = ToJson(map);
  ASSERT_GE(live["lines"].size(), 4u);
  EXPECT_EQ(replayed["lines"], live["lines"]);
  EXPECT_EQ(replayed["objects"], live["objects"]);
  EXPECT_EQ(replayed["room"], live["room"]);
  EXPECT_EQ(replayed["pose"], live["pose"]);
  EXPECT_EQ(replayed["pose_cov"], live["pose_cov"]);
  EXPECT_EQ(replayed["trajectory"], live["trajectory"]);
}

TEST(ReplayTest, NotedStartAndStopAreReplayedAtTheirTime) {
  const Recorded rec = RecordMission("wall_follow_fig14", 12.0, 10.013, /*notes=*/true);
  robot::MapSnapshot map;
  const ReplayStats s = ReplayLines(rec.lines, &map, /*noted=*/true);
  EXPECT_EQ(s.starts, 1u);
  EXPECT_EQ(s.stops, 1u);
  EXPECT_EQ(s.stop_frames, 1u);
  EXPECT_EQ(s.ticks, rec.ticks);
  EXPECT_EQ(s.commands_differed, 0u);
  EXPECT_EQ(s.states_differed, 0u);
  EXPECT_EQ(ToJson(map)["lines"], ToJson(rec.map)["lines"]);
}

TEST(ReplayTest, WithoutNotesTheStopIsReadFromTheHeartbeat) {
  const Recorded rec = RecordMission("wall_follow_fig14", 12.0, 10.013);
  ASSERT_EQ(rec.map.state, control::MissionState::kIdle);
  robot::MapSnapshot map;
  const ReplayStats s = ReplayLines(rec.lines, &map);
  // The stop frame is replayed as a tick (it cannot be told from one); the next
  // heartbeat (10 Hz) says idle: Stop. The commands in between differ.
  EXPECT_EQ(s.stop_frames, 0u);
  EXPECT_EQ(s.stops, 1u);
  EXPECT_EQ(s.ticks, rec.ticks + 1);
  EXPECT_GE(s.commands_differed, 1u);
  EXPECT_LE(s.commands_differed, 6u);
  EXPECT_EQ(map.state, control::MissionState::kIdle);
  EXPECT_EQ(ToJson(map)["lines"], ToJson(rec.map)["lines"]);
  EXPECT_EQ(ToJson(map)["pose"], ToJson(rec.map)["pose"]);
}

std::vector<std::string> ReadLines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

TEST(BusRecorderTest, WritesTheHeaderAndEveryFrameAndRotatesAtMaxBytes) {
  const std::string dir = testing::MakeTempDir();
  RecordSettings settings;
  settings.max_bytes = 65536;
  settings.files = 3;
  settings.buffer_bytes = 1 << 20;
  {
    std::ofstream(dir + "/bus.log") << "an older run\n";  // rotated away at open
    BusRecorder rec(dir, settings, {1700000000000000000, 2, 0.02}, "vcan0");
    std::string error;
    ASSERT_TRUE(rec.Open(&error)) << error;
    can_frame f{};
    f.can_id = 0x110;
    f.can_dlc = 7;
    // 6000 lines of 45 bytes: 270 kB, four files of 64 kB and more.
    for (int i = 0; i < 6000; ++i) rec.Record(f, i * 0.002);
    rec.Close();
    const RecorderStats s = rec.stats();
    EXPECT_EQ(s.lines + s.dropped, 6000u);
    EXPECT_EQ(s.dropped, 0u);
    EXPECT_EQ(s.rotations, 5u);  // the older run's file, then at 64 kB four times
    EXPECT_TRUE(s.error.empty()) << s.error;
  }
  // Three files (bus.log, .1, .2), the older run's gone; each starts with the header.
  EXPECT_FALSE(std::filesystem::exists(dir + "/bus.log.3"));
  size_t frames = 0;
  for (const char* name : {"/bus.log.2", "/bus.log.1", "/bus.log"}) {
    const auto lines = ReadLines(dir + name);
    ASSERT_FALSE(lines.empty()) << name;
    EXPECT_EQ(lines[0], "# irslamd-record v1 origin=1700000000.000000000 time_scale=2 period_s=0.02") << name;
    EXPECT_LE(std::filesystem::file_size(dir + name), 65536u) << name;
    frames += lines.size() - 1;
  }
  // The newest file's last line: frame 5999 at robot time 11.998 s = 5.999 s of log time at 2x.
  const auto last = ReadLines(dir + "/bus.log").back();
  EXPECT_EQ(last, "(1700000005.999000) vcan0 110#00000000000000");
  // Full files hold (65536 - 75) / 45 = 1454 lines; the two oldest files went.
  EXPECT_EQ(ReadLines(dir + "/bus.log.1").size(), 1455u);
  EXPECT_EQ(frames, 2 * 1454u + (6000u - 4 * 1454u));
  std::filesystem::remove_all(dir);
}

TEST(BusRecorderTest, WithASmallBufferEveryLineIsWrittenOrCountedAsDropped) {
  const std::string dir = testing::MakeTempDir();
  RecordSettings settings;
  settings.buffer_bytes = 4096;  // about 100 lines
  BusRecorder rec(dir, settings, {0, 1, 0.02}, "can0");
  std::string error;
  ASSERT_TRUE(rec.Open(&error)) << error;
  can_frame f{};
  f.can_id = 0x080;
  f.can_dlc = 6;
  for (int i = 0; i < 20000; ++i) rec.Record(f, i * 1e-6);
  rec.Close();
  const RecorderStats s = rec.stats();
  EXPECT_EQ(s.lines + s.dropped, 20000u);
  EXPECT_EQ(ReadLines(dir + "/bus.log").size(), s.lines + 1);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace irslam
