// irslam-replay: a recorded bus log through the same core, offline (contracts §7).
//   irslam-replay LOG... [--map-out MAP.json] [--svg MAP.svg] [--config FILE] [--time-scale K]
// LOG: candump -L text (irslamd's [record] files, irslam-candump, can-utils' candump);
// several files are read in the order given (rotated recordings: oldest first).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <string>
#include <variant>
#include <vector>

#include "io/file_io.h"
#include "daemon/candump_log.h"
#include "daemon/config.h"
#include "daemon/core_json.h"
#include "daemon/map_pgm.h"
#include "daemon/map_svg.h"
#include "daemon/replay.h"
#include "proto/codec.h"

namespace irslam {
namespace {

// Reads LOG files line by line; Next() gives each line with its file and number.
class LogReader {
 public:
  explicit LogReader(std::vector<std::string> paths) : paths_(std::move(paths)) {}
  // false at the end or on an error (then *error is set).
  bool Next(LogLine* out, std::string* error, std::string* text = nullptr) {
    for (;;) {
      if (!in_.is_open()) {
        if (file_ >= paths_.size()) return false;
        in_.open(paths_[file_]);
        line_no_ = 0;
        if (!in_) {
          *error = paths_[file_] + ": cannot open";
          return false;
        }
      }
      std::string line;
      if (!std::getline(in_, line)) {
        if (in_.bad()) {
          *error = Where() + ": read error";
          return false;
        }
        in_.close();
        ++file_;
        continue;
      }
      ++line_no_;
      std::string why;
      if (!ParseLogLine(line, out, &why)) {
        *error = Where() + ": " + why + (in_.eof() ? " (the last line: truncated log?)" : "");
        return false;
      }
      if (out->kind == LogLine::Kind::kComment && !header_) header_ = ParseRecordHeader(line);
      if (text) *text = std::move(line);
      return true;
    }
  }
  std::string Where() const { return paths_[file_] + ":" + std::to_string(line_no_); }
  const std::optional<RecordHeader>& header() const { return header_; }

 private:
  std::vector<std::string> paths_;
  size_t file_ = 0;
  std::ifstream in_;
  uint64_t line_no_ = 0;
  std::optional<RecordHeader> header_;
};

struct Timing {
  int64_t origin_ns = 0;
  double time_scale = 1;
  const char* source = "";
  std::optional<double> measured;  // the ENCODER stamps' fit before rounding
  std::optional<int64_t> feed_from_ns;  // a bystander's log: from the daemon's first frame
  bool noted = false;                   // irslamd's recording: start and stop are noted
};

// The time origin and scale: the recorder's header, else the first frame and the
// controller's ENCODER stamps against the log's (the WHEEL_CMD spacing when there are
// too few), or --time-scale.
bool FindTiming(const std::vector<std::string>& logs, double period_s, double given_scale, Timing* timing,
                std::string* error) {
  // 5 minutes of a 100 Hz controller: the fit's error is the receive latency over the
  // span, far under the 3 % the rounding allows.
  constexpr size_t kFitFrames = 30000;
  constexpr size_t kCommands = 2000;
  LogReader reader(logs);
  LogLine line;
  std::optional<int64_t> first, first_daemon;
  std::vector<int64_t> cmds;
  ControllerClockFit fit;
  while (fit.frames() < kFitFrames && reader.Next(&line, error)) {
    if (reader.header()) break;
    if (line.kind != LogLine::Kind::kFrame) continue;
    if (!first) first = line.stamp_ns;
    if (line.frame.can_id == proto::kWheelCmdId && cmds.size() < kCommands) cmds.push_back(line.stamp_ns);
    if (line.frame.can_id == proto::kEncoderId) {
      const proto::DecodeResult r = proto::Decode(line.frame);
      if (const auto* e = r.ok() ? std::get_if<proto::EncoderCounts>(&r.message) : nullptr) {
        fit.Add(line.stamp_ns, e->timestamp_ms);
      }
    }
    if (!first_daemon && (line.frame.can_id == proto::kWheelCmdId || line.frame.can_id == proto::kDaemonHeartbeatId)) {
      first_daemon = line.stamp_ns;
    }
  }
  if (!error->empty()) return false;
  if (reader.header()) {
    timing->origin_ns = reader.header()->origin_ns;
    timing->time_scale = given_scale > 0 ? given_scale : reader.header()->time_scale;
    timing->source = given_scale > 0 ? "--time-scale" : "the recorder's header";
    timing->noted = true;
    return true;
  }
  if (!first) {
    *error = "no CAN frame in the log";
    return false;
  }
  timing->origin_ns = *first;
  if (given_scale > 0) {
    timing->time_scale = given_scale;
    timing->source = "--time-scale";
  } else if (const auto k = fit.Scale()) {
    timing->time_scale = *k;
    timing->source = "the controller's ENCODER stamps";
    timing->measured = fit.Measured();
  } else {
    const auto k2 = EstimateTimeScale(cmds, period_s);
    if (!k2) {
      *error = "no recorder header and too few ENCODER or WHEEL_CMD frames to tell the time scale: give --time-scale";
      return false;
    }
    timing->time_scale = *k2;
    timing->source = "the WHEEL_CMD spacing";
  }
  // irslamd hears the controller from when it opens the bus, about one control
  // period before its first frame (its first tick): what came before, it never saw.
  // Robot time 0 is put there too, as near the daemon's own origin as the log tells.
  if (first_daemon) {
    timing->feed_from_ns = *first_daemon - static_cast<int64_t>(period_s / timing->time_scale * 1e9);
    timing->origin_ns = *timing->feed_from_ns;
  }
  return true;
}

// CPU seconds of this process (the replay's own work, whatever else the machine runs).
double CpuSeconds() {
  timespec ts{};
  ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

nlohmann::json StatsJson(const ReplayStats& s, const Timing& timing, double seconds, double cpu) {
  const double span = s.last_t - s.first_t;
  return {{"frames", s.frames},
          {"ticks", s.ticks},
          {"stop_frames", s.stop_frames},
          {"starts", s.starts},
          {"stops", s.stops},
          {"commands_matched", s.commands_matched},
          {"commands_differed", s.commands_differed},
          {"heartbeats", s.heartbeats},
          {"states_differed", s.states_differed},
          {"ignored", s.ignored},
          {"skipped", s.skipped},
          {"started_t", s.started_t ? nlohmann::json(*s.started_t) : nlohmann::json()},
          {"robot_time_s", span},
          {"time_scale", timing.time_scale},
          {"time_scale_measured", timing.measured ? nlohmann::json(*timing.measured) : nlohmann::json()},
          {"wall_s", seconds},
          {"cpu_s", cpu},
          {"speed", seconds > 0 ? span / seconds : 0.0},
          {"speed_cpu", cpu > 0 ? span / cpu : 0.0}};
}

struct ReplayArgs {
  std::vector<std::string> logs;
  std::string map_out, svg_out, pgm_out, config_path, stats_out;
  double pgm_res = kDefaultPgmResolutionM;
  double time_scale = 0;
};

void AddOptions(CLI::App& app, ReplayArgs* a) {
  app.add_option("log", a->logs, "candump -L log(s), oldest first")->required();
  app.add_option("--map-out", a->map_out, "Write the map here (contracts §4)");
  app.add_option("--svg", a->svg_out, "Draw the map as SVG");
  app.add_option("--pgm", a->pgm_out, "Write the map as an occupancy grid FILE.pgm and FILE.yaml (ROS map_server)");
  app.add_option("--pgm-resolution", a->pgm_res, "Cell size of --pgm in metres")
      ->check(CLI::Range(0.005, 1.0))
      ->capture_default_str();
  app.add_option("--config", a->config_path, "The daemon's config file (the same as when recording)");
  app.add_option("--time-scale", a->time_scale,
                 "Robot seconds per log second (default: the recorder's header, else fitted from the ENCODER stamps)")
      ->check(CLI::Range(0.01, 1000.0));
  app.add_option("--stats", a->stats_out, "Write the replay's counts as JSON here");
}

// Feeds every frame and noted event of the logs to the replay, in order. false
// (with *error set) on a read error or a line earlier than the one before.
bool FeedLogs(const std::vector<std::string>& logs, Replay* replay, std::string* error) {
  LogReader reader(logs);
  LogLine line;
  std::optional<int64_t> last_stamp;
  std::string text;
  while (reader.Next(&line, error, &text)) {
    if (line.kind == LogLine::Kind::kComment) {
      if (const auto event = ParseEventComment(text)) {
        line.stamp_ns = event->stamp_ns;  // checked for order below, like a frame
        if (last_stamp && line.stamp_ns < *last_stamp) {
          *error = reader.Where() + ": event before the previous line's time";
          return false;
        }
        last_stamp = line.stamp_ns;
        replay->OnEvent(*event);
      }
      continue;
    }
    if (line.kind != LogLine::Kind::kFrame && line.kind != LogLine::Kind::kForeign) continue;
    // The core's time never runs backwards: a log out of order (files in the wrong
    // order, two logs mixed) is refused, not half replayed.
    if (last_stamp && line.stamp_ns < *last_stamp) {
      char b[64];
      std::snprintf(b, sizeof b, "%.6f", static_cast<double>(*last_stamp - line.stamp_ns) * 1e-9);
      *error = reader.Where() + ": time stamp " + b + " s before the previous line's (files out of order?)";
      return false;
    }
    last_stamp = line.stamp_ns;
    replay->Feed(line);
  }
  return error->empty();
}

// The map (JSON, SVG, PGM) and the stats, where the command line asked for them.
bool WriteOutputs(const ReplayArgs& a, const nlohmann::json& map, const nlohmann::json& stats, std::string* error) {
  if (!a.map_out.empty() && !WriteFileReplacing(a.map_out, map.dump(1) + "\n")) {
    *error = "cannot write " + a.map_out;
    return false;
  }
  if (!a.svg_out.empty() && !WriteFileReplacing(a.svg_out, RenderMapSvg(map, nullptr, nullptr))) {
    *error = "cannot write " + a.svg_out;
    return false;
  }
  if (!a.pgm_out.empty() && !WritePgmMap(map, a.pgm_out, a.pgm_res, error)) return false;
  if (!a.stats_out.empty() && !WriteFileReplacing(a.stats_out, stats.dump(1) + "\n")) {
    *error = "cannot write " + a.stats_out;
    return false;
  }
  return true;
}

std::string Fixed(double x, int digits) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*f", digits, x);
  return buf;
}

void PrintSummary(const ReplayStats& s, const Timing& timing, double seconds, double cpu, const nlohmann::json& map) {
  std::fprintf(stderr,
               "irslam-replay: %llu frames, %llu ticks (time scale %g from %s%s); %s; commands as recorded %llu of %llu, "
               "states %llu of %llu; %.1f s of robot time in %.3f s (%.0fx real time; CPU %.3f s: %.0fx); state %s, %zu lines, "
               "%zu objects\n",
               static_cast<unsigned long long>(s.frames), static_cast<unsigned long long>(s.ticks), timing.time_scale,
               timing.source,
               timing.measured ? (", measured " + Fixed(*timing.measured, 4)).c_str() : "",
               s.started_t ? ("started at t=" + std::to_string(*s.started_t) + " s").c_str() : "never started",
               static_cast<unsigned long long>(s.commands_matched),
               static_cast<unsigned long long>(s.commands_matched + s.commands_differed),
               static_cast<unsigned long long>(s.heartbeats - s.states_differed),
               static_cast<unsigned long long>(s.heartbeats), s.last_t - s.first_t, seconds,
               seconds > 0 ? (s.last_t - s.first_t) / seconds : 0.0, cpu, cpu > 0 ? (s.last_t - s.first_t) / cpu : 0.0,
               map["state"].get<std::string>().c_str(),
               map["lines"].size(), map["objects"].size());
  if (!s.start_error.empty()) std::fprintf(stderr, "irslam-replay: a start was refused: %s\n", s.start_error.c_str());
}

int Main(int argc, char** argv) {
  CLI::App app{"irslam-replay: feed a recorded candump -L log through irslamd's core offline and write its map"};
  ReplayArgs args;
  AddOptions(app, &args);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  robot::CoreOptions core = robot::DefaultCoreOptions();
  std::string error;
  if (!args.config_path.empty() && !LoadCoreConfigFile(args.config_path, &core, &error)) {
    std::fprintf(stderr, "irslam-replay: %s\n", error.c_str());
    return 2;
  }
  Timing timing;
  if (!FindTiming(args.logs, core.period_s, args.time_scale, &timing, &error)) {
    std::fprintf(stderr, "irslam-replay: %s\n", error.c_str());
    return 1;
  }
  const auto begin = std::chrono::steady_clock::now();
  const double cpu_begin = CpuSeconds();
  Replay replay(core, timing.origin_ns, timing.time_scale);
  if (timing.feed_from_ns) replay.SkipControllerFramesBefore(*timing.feed_from_ns);
  if (timing.noted) replay.SetNoted();
  if (!FeedLogs(args.logs, &replay, &error)) {
    std::fprintf(stderr, "irslam-replay: %s\n", error.c_str());
    return 1;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  const double cpu = CpuSeconds() - cpu_begin;
  const nlohmann::json map = ToJson(replay.core().Map());
  if (!WriteOutputs(args, map, StatsJson(replay.stats(), timing, seconds, cpu), &error)) {
    std::fprintf(stderr, "irslam-replay: %s\n", error.c_str());
    return 1;
  }
  PrintSummary(replay.stats(), timing, seconds, cpu, map);
  return 0;
}

}  // namespace
}  // namespace irslam

int main(int argc, char** argv) { return irslam::Main(argc, argv); }
