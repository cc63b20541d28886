// irslamd: the irslam navigation daemon (contracts.md §2).
//   irslamd --can IFACE [--socket PATH] [--config FILE] [--time-scale K]
#include <malloc.h>
#include <systemd/sd-daemon.h>

#include <CLI/CLI.hpp>
#include <boost/asio/io_context.hpp>
#include <cstdio>
#include <cstdlib>

#include "daemon/config.h"
#include "daemon/irslamd.h"

int main(int argc, char** argv) {
  // One malloc arena for every thread: the API and map-writer threads each got
  // their own (~0.5 MB resident at the end of a mission, measured), and their
  // allocation rate is far too low to contend (issue 15's RSS budget).
  ::mallopt(M_ARENA_MAX, 1);
  // Blocks of 128 KB and more always mmap'ed, returned to the kernel when
  // freed. Left to glibc, the threshold rises to the largest such block freed
  // (a map's encoded text, ~0.1-0.3 MB): from then on those blocks come from
  // the heap and leave it fragmented, and a calloc'ed table (the planner's
  // distances, control/path_planner.h) is memset page by page instead of
  // staying untouched where unused (issue 15's RSS budget).
  ::mallopt(M_MMAP_THRESHOLD, 128 * 1024);
  CLI::App app{"irslamd: line-feature SLAM and exploration for a robot with IR range sensors"};
  irslam::DaemonOptions options;
  bool print_config = false;
  app.add_option("--can", options.can_iface, "CAN interface (can0, vcan0) or unix:PATH");
  app.add_option("--socket", options.socket_path, "Control socket path")
      ->capture_default_str();
  app.add_option("--config", options.config_path, "Config file (JSON with comments)");
  app.add_option("--time-scale", options.time_scale,
                 "Robot time runs K times faster than wall time (tests, demos)")
      ->check(CLI::Range(0.01, 1000.0))
      ->capture_default_str();
  std::string state_dir;
  app.add_option("--state-dir", state_dir, "Where the map is saved (overrides state.dir)");
  int max_clients = 0;
  app.add_option("--max-clients", max_clients, "API client limit (overrides api.max_clients)");
  app.add_flag("--print-config", print_config, "Print the effective configuration and exit");
  bool print_default_config = false;
  app.add_flag("--print-default-config", print_default_config,
               "Print the commented default config file (daemon/irslamd.conf) and exit");
  app.add_option("--test-hang-at", options.test_hang_at_s,
                 "Test aid: hang the control loop at this robot time (watchdog tests)")
      ->group("Testing");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  irslam::DaemonSettings settings;  // the built-in defaults, then the config file's
  std::string error;
  if (!options.config_path.empty() && !irslam::LoadConfigFile(options.config_path, &settings, &error)) {
    std::fprintf(stderr, "irslamd: %s\n", error.c_str());
    return 2;
  }
  if (!state_dir.empty()) settings.state_dir = state_dir;
  options.limits.max_clients = static_cast<size_t>(max_clients > 0 ? max_clients : settings.api.max_clients);
  options.limits.max_line_bytes = static_cast<size_t>(settings.api.max_line_bytes);
  options.limits.idle_timeout_s = settings.api.idle_timeout_s;
  options.limits.max_pending_bytes = static_cast<size_t>(settings.api.max_pending_bytes);
  if (print_default_config) {
    std::printf("%s", irslam::DocumentedConfig(irslam::DaemonSettings()).c_str());
    return 0;
  }
  if (print_config) {
    std::printf("%s\n", irslam::DumpConfig(settings).c_str());
    return 0;
  }
  if (options.can_iface.empty()) {
    std::fprintf(stderr, "irslamd: --can IFACE is required (can0, vcan0 or unix:PATH)\n");
    return 2;
  }
  // systemd's side: where to notify, and whether (how often) to feed the watchdog.
  if (const char* notify = std::getenv("NOTIFY_SOCKET")) options.notify_socket = notify;
  if (sd_watchdog_enabled(0, &options.watchdog_usec) <= 0) options.watchdog_usec = 0;
  boost::asio::io_context io;
  irslam::Daemon daemon(io, options, settings);
  if (!daemon.Open(&error)) {
    std::fprintf(stderr, "irslamd: %s\n", error.c_str());
    return 1;
  }
  return daemon.Run();
}
