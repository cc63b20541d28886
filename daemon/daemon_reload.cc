// irslamd's Daemon (daemon/irslamd.h): SIGHUP reloads the --config file. A file
// that does not validate changes nothing; a valid one applies at once when no
// mission runs, else when the mission ends (ApplyOptions, in irslamd.cc).
#include <cstdio>

#include "daemon/config.h"
#include "daemon/irslamd.h"

namespace irslam {

void Daemon::Reload() {
  if (options_.config_path.empty()) {
    std::fprintf(stderr, "<5>irslamd: SIGHUP: no --config file, nothing to reload\n");
    return;
  }
  DaemonSettings fresh;  // the built-in defaults
  std::string error;
  if (!LoadConfigFile(options_.config_path, &fresh, &error)) {
    std::fprintf(stderr, "<3>irslamd: reload failed, keeping the running config: %s\n", error.c_str());
    return;
  }
  const auto s = core_->state();
  if (s == control::MissionState::kIdle || s == control::MissionState::kDone) {
    pending_options_.reset();
    ApplyOptions(std::move(fresh));  // the map service keeps the old core's map
    std::fprintf(stderr, "<5>irslamd: config reloaded from %s\n", options_.config_path.c_str());
  } else {
    pending_options_ = std::move(fresh);
    std::fprintf(stderr, "<5>irslamd: config from %s validated; applied when the mission ends\n",
                 options_.config_path.c_str());
  }
}

void Daemon::ApplyPendingOptions() {
  const auto s = core_->state();
  if (!pending_options_ || (s != control::MissionState::kIdle && s != control::MissionState::kDone)) return;
  ApplyOptions(*std::move(pending_options_));
  pending_options_.reset();
  std::fprintf(stderr, "<5>irslamd: config from %s applied\n", options_.config_path.c_str());
}

}  // namespace irslam
