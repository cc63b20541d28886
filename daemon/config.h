// The one configuration file of irslamd (and of `irslam-sim run`): JSON with
// // comments, every key optional with a documented default (daemon/irslamd.conf,
// generated from the option tables), unknown keys rejected with their full name.
#ifndef IRSLAM_DAEMON_CONFIG_H_
#define IRSLAM_DAEMON_CONFIG_H_

#include <string>
#include <string_view>

#include "daemon/daemon_settings.h"
#include "robot/robot_core.h"

namespace irslam {

// Parses config text over the defaults. On error returns false and sets *error to
// one line naming the key or the position of the problem.
bool ParseConfig(std::string_view text, DaemonSettings* settings, std::string* error);
// Reads and parses a file ("config: cannot read FILE: ..." on I/O errors).
bool LoadConfigFile(const std::string& path, DaemonSettings* settings, std::string* error);
// The same for a tool that runs only the core (irslam-sim, irslam-replay, the
// test tools): the whole file is checked, its core part is set over *core.
bool LoadCoreConfigFile(const std::string& path, robot::CoreOptions* core, std::string* error);
// The effective configuration as JSON (what `irslamd --print-config` shows).
std::string DumpConfig(const DaemonSettings& settings);
// The commented config file for these settings: every key with what it does, its
// unit and bounds (daemon/irslamd.conf is this for the defaults; a test checks it).
std::string DocumentedConfig(const DaemonSettings& settings);

}  // namespace irslam

#endif  // IRSLAM_DAEMON_CONFIG_H_
