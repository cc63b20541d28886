// irslamctl: command-line client of irslamd (contracts.md §3).
//   irslamctl [--socket PATH] status [--json] | start [--mode M] [--fresh] | clean | stop |
//             map [--out map.json] [--svg map.svg] [--pgm map.pgm] | wait --state STATE [--timeout S] | watch
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <string>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "daemon/map_pgm.h"
#include "daemon/map_svg.h"
#include "daemon/rpc_client.h"
#include "io/file_io.h"

namespace irslam {
namespace {

constexpr double kCallTimeout = 5.0;

int Fail(const std::string& msg) {
  std::fprintf(stderr, "irslamctl: %s\n", msg.c_str());
  return 1;
}

std::string Num(const nlohmann::json& j, int prec = 3) {
  if (!j.is_number()) return "-";
  char b[32];
  std::snprintf(b, sizeof b, "%.*f", prec, j.get<double>());
  return b;
}

std::string StatusLine(const nlohmann::json& s) {
  const auto& p = s.value("pose", nlohmann::json::array({0, 0, 0}));
  const auto& can = s.value("can", nlohmann::json::object());
  const auto& per = s.value("period", nlohmann::json::object());
  char b[512];
  std::snprintf(b, sizeof b,
                "%-14s %-12s t=%7.1fs pose=(%6.2f,%6.2f,%6.1fdeg) lines=%-3d objects=%-2d "
                "can rx=%llu tx=%llu drop=%llu link=%s jitter=%.1fms overruns=%llu",
                s.value("state", "?").c_str(), s.value("behaviour", "").c_str(),
                s.value("robot_time", 0.0), p[0].get<double>(), p[1].get<double>(),
                p[2].get<double>() * 180 / M_PI, s.value("lines", 0), s.value("objects", 0),
                can.value("rx", 0ULL), can.value("tx", 0ULL),
                can.value("rx_dropped", 0ULL) + can.value("tx_dropped", 0ULL),
                can.value("link_up", false) ? "up" : "DOWN", per.value("jitter_max", 0.0) * 1e3,
                per.value("overruns", 0ULL));
  std::string line = b;
  // Cleaning: a progress bar with the percentage and the time left.
  if (s.contains("cleaning") && s["cleaning"].is_object()) {
    const auto& c = s["cleaning"];
    const double f = std::clamp(c.value("fraction", 0.0), 0.0, 1.0);
    const int n = static_cast<int>(std::lround(f * 20));
    const double eta = c.value("eta_s", 0.0);
    char bar[160];
    std::snprintf(bar, sizeof bar, " clean [%s%s] %5.1f%% cells %d/%d eta %dm%02ds", std::string(n, '#').c_str(),
                  std::string(20 - n, '.').c_str(), 100 * f, c.value("cells_done", 0), c.value("cells_total", 0),
                  static_cast<int>(eta) / 60, static_cast<int>(eta) % 60);
    line = bar + std::string(" ") + line;
    line = line.substr(0, line.find(" can rx"));
  }
  return line;
}

void PrintStatus(const nlohmann::json& s) {
  std::printf("state:      %s", s.value("state", "?").c_str());
  if (!s.value("reason", "").empty()) std::printf(" (%s)", s.value("reason", "").c_str());
  std::printf("\nbehaviour:  %s\n", s.value("behaviour", "").c_str());
  const auto& p = s["pose"];
  const auto& sd = s.value("pose_std", nlohmann::json::array({0, 0, 0}));
  std::printf("pose:       x=%s y=%s theta=%s rad  (std %s m, %s m, %s rad)\n", Num(p[0]).c_str(),
              Num(p[1]).c_str(), Num(p[2]).c_str(), Num(sd[0]).c_str(), Num(sd[1]).c_str(),
              Num(sd[2]).c_str());
  std::printf("map:        %d lines, %d objects, %s m driven\n", s.value("lines", 0),
              s.value("objects", 0), Num(s.value("distance", 0.0), 1).c_str());
  if (s.contains("cleaning") && s["cleaning"].is_object()) {
    const auto& c = s["cleaning"];
    std::printf("cleaning:   %s, cells %d/%d, %s of %s m2 (%s %%), path %s m, eta %s s, unreachable %s m2\n",
                c.value("state", "?").c_str(), c.value("cells_done", 0), c.value("cells_total", 0),
                Num(c.value("covered_m2", 0.0), 2).c_str(), Num(c.value("total_m2", 0.0), 2).c_str(),
                Num(100 * c.value("fraction", 0.0), 1).c_str(), Num(c.value("path_m", 0.0), 1).c_str(),
                Num(c.value("eta_s", 0.0), 0).c_str(), Num(c.value("unreachable_m2", 0.0), 2).c_str());
  }
  const auto& ctl = s.value("controller", nlohmann::json::object());
  std::printf("controller: %s, faults=0x%02x bumpers=0x%02x battery=%s V\n",
              ctl.value("alive", false) ? "alive" : "LOST", ctl.value("faults", 0),
              ctl.value("bumpers", 0), Num(ctl.value("battery", 0.0), 2).c_str());
  const auto& can = s.value("can", nlohmann::json::object());
  std::printf("can:        %s link=%s rx=%llu tx=%llu rx_dropped=%llu tx_dropped=%llu errors=%llu\n",
              can.value("iface", "?").c_str(), can.value("link_up", false) ? "up" : "DOWN",
              can.value("rx", 0ULL), can.value("tx", 0ULL), can.value("rx_dropped", 0ULL),
              can.value("tx_dropped", 0ULL), can.value("error_frames", 0ULL));
  const auto& fr = s.value("frames", nlohmann::json::object());
  std::printf("frames:     encoder=%llu ir=%llu status=%llu unknown_id=%llu wrong_dlc=%llu "
              "seq_gaps=%llu/%llu/%llu\n",
              fr.value("encoder", 0ULL), fr.value("ir", 0ULL), fr.value("status", 0ULL),
              fr.value("unknown_id", 0ULL), fr.value("wrong_dlc", 0ULL),
              fr.value("seq_gap_encoder", 0ULL), fr.value("seq_gap_ir", 0ULL),
              fr.value("seq_gap_status", 0ULL));
  const auto& per = s.value("period", nlohmann::json::object());
  std::printf("period:     %s s target, %llu ticks, %llu overruns, jitter mean %s ms max %s ms\n",
              Num(per.value("target", 0.0)).c_str(), per.value("ticks", 0ULL),
              per.value("overruns", 0ULL), Num(per.value("jitter_mean", 0.0) * 1e3, 2).c_str(),
              Num(per.value("jitter_max", 0.0) * 1e3, 2).c_str());
  std::printf("uptime:     %s s\n", Num(s.value("uptime", 0.0), 1).c_str());
}

// What the command line asked for: the subcommand that was chosen (the others
// stay null after parsing) and the options of each.
struct CtlArgs {
  std::string socket_path;
  CLI::App* status = nullptr;
  bool json_out = false;
  CLI::App* start = nullptr;
  std::string mode;
  bool fresh = false;
  CLI::App* clean = nullptr;
  CLI::App* stop = nullptr;
  CLI::App* map = nullptr;
  std::string out_path, svg_path, pgm_path;
  double pgm_res = kDefaultPgmResolutionM;
  CLI::App* wait = nullptr;
  std::string want_state;
  double timeout = 0;
  CLI::App* watch = nullptr;
};

void AddCommands(CLI::App& app, CtlArgs* a) {
  app.add_option("--socket", a->socket_path,
                 "irslamd control socket (default $IRSLAM_SOCKET or /run/irslam/irslamd.sock)");
  app.require_subcommand(1);
  a->status = app.add_subcommand("status", "Show the daemon's status");
  a->status->add_flag("--json", a->json_out, "Print the raw JSON");
  a->start = app.add_subcommand("start", "Start the mission (exploration; --mode clean: then clean)");
  a->start->add_option("--mode", a->mode, "explore (map only) or clean (map, clean, return to the start); "
                                          "default: the daemon's mission.mode")
      ->check(CLI::IsMember({"explore", "clean"}));
  a->start->add_flag("--fresh", a->fresh,
                     "Forget the saved map: explore from nothing instead of relocalising in it");
  a->clean = app.add_subcommand("clean", "Start the mission in mode clean");
  a->stop = app.add_subcommand("stop", "Stop the robot");
  a->map = app.add_subcommand("map", "Fetch the map");
  a->map->add_option("--out", a->out_path, "Write the map JSON here (default: stdout)");
  a->map->add_option("--svg", a->svg_path, "Also draw it as SVG");
  a->map->add_option("--pgm", a->pgm_path, "Also write an occupancy grid FILE.pgm and FILE.yaml (ROS map_server)");
  a->map->add_option("--pgm-resolution", a->pgm_res, "Cell size of --pgm in metres")
      ->check(CLI::Range(0.005, 1.0))
      ->capture_default_str();
  a->wait = app.add_subcommand("wait", "Wait until the mission reaches a state");
  a->wait->add_option("--state", a->want_state,
                      "idle, relocalize, wall_follow, model, go_to_p1, contour_follow, clean, return_home, done, fault")
      ->required();
  a->wait->add_option("--timeout", a->timeout, "Give up after this many seconds (default: never)");
  a->watch = app.add_subcommand("watch", "Show state, pose, map and CAN counters live");
}

int RunStatus(RpcClient& client, const CtlArgs& a) {
  std::string error;
  auto s = client.Call("status", nlohmann::json::object(), kCallTimeout, &error);
  if (!s) return Fail(error);
  if (a.json_out) {
    std::printf("%s\n", s->dump(2).c_str());
  } else {
    PrintStatus(*s);
  }
  return 0;
}

// start, clean and stop: one call, the state it answers with.
int RunMissionCommand(RpcClient& client, const CtlArgs& a) {
  const bool start = a.start->parsed(), clean = a.clean->parsed();
  nlohmann::json params = nlohmann::json::object();
  if (start && !a.mode.empty()) params["mode"] = a.mode;
  if (start && a.fresh) params["fresh"] = true;
  std::string error;
  auto r = client.Call(start ? "start" : (clean ? "clean" : "stop"), params, kCallTimeout, &error);
  if (!r) return Fail(error);
  std::printf("state: %s\n", r->value("state", "?").c_str());
  return 0;
}

int RunMap(RpcClient& client, const CtlArgs& a) {
  std::string error;
  auto m = client.Call("map", nlohmann::json::object(), 30, &error);
  if (!m) return Fail(error);
  if (a.out_path.empty() && a.svg_path.empty() && a.pgm_path.empty()) {
    std::printf("%s\n", m->dump(1).c_str());
  }
  if (!a.out_path.empty() && !WriteFileReplacing(a.out_path, m->dump(1) + "\n")) {
    return Fail("cannot write " + a.out_path);
  }
  if (!a.svg_path.empty() && !WriteFileReplacing(a.svg_path, RenderMapSvg(*m, nullptr, nullptr))) {
    return Fail("cannot write " + a.svg_path);
  }
  if (!a.pgm_path.empty() && !WritePgmMap(*m, a.pgm_path, a.pgm_res, &error)) return Fail(error);
  return 0;
}

// wait and watch: follow the status notifications, until the wanted state
// (wait) or for ever (watch, one line per notification).
int RunFollow(RpcClient& client, const CtlArgs& a) {
  const bool wait = a.wait->parsed();
  std::string error;
  auto r = client.Call("subscribe", {{"rate", wait ? 20 : 4}}, kCallTimeout, &error);
  if (!r) return Fail(error);
  const auto t0 = std::chrono::steady_clock::now();
  const bool tty = ::isatty(STDOUT_FILENO);
  for (;;) {
    double left = 3600 * 24;
    if (wait && a.timeout > 0) {
      left = a.timeout - std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (left <= 0) return Fail("timed out waiting for state " + a.want_state);
    }
    auto s = client.NextNotification(std::min(left, 5.0), &error);
    if (!s) {
      if (error.rfind("timed out", 0) == 0) continue;
      return Fail(error);
    }
    if (wait) {
      if (s->value("state", "") == a.want_state) return 0;
      continue;
    }
    std::printf(tty ? "\r\033[K%s" : "%s\n", StatusLine(*s).c_str());
    std::fflush(stdout);
  }
}

}  // namespace
}  // namespace irslam

int main(int argc, char** argv) {
  using namespace irslam;
  CLI::App app{"irslamctl: control and watch irslamd"};
  CtlArgs args;
  AddCommands(app, &args);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (args.socket_path.empty()) args.socket_path = DefaultSocketPath();
  RpcClient client;
  std::string error;
  if (!client.Connect(args.socket_path, &error)) return Fail(error);
  if (*args.status) return RunStatus(client, args);
  if (*args.start || *args.stop || *args.clean) return RunMissionCommand(client, args);
  if (*args.map) return RunMap(client, args);
  if (*args.wait || *args.watch) return RunFollow(client, args);
  return 0;
}
