// Everything the config file sets for irslamd: the pure core's options
// (robot::CoreOptions) plus the daemon's own settings, which the core never
// sees (the control socket, the GPIO lines, the bus recording, the state
// directory). The file's sections are laid out in daemon/config_schema.cc;
// irslam-sim, irslam-replay and the test tools take only the .core part.
#ifndef IRSLAM_DAEMON_DAEMON_SETTINGS_H_
#define IRSLAM_DAEMON_DAEMON_SETTINGS_H_

#include <string>

#include "drivers/gpio_settings.h"
#include "robot/robot_core.h"

namespace irslam {

// The control socket's settings (config section [api]).
struct ApiSettings {
  std::string socket_group;    // chgrp the socket to this group ("": the daemon's)
  std::string read_group;      // may call status/map/subscribe ("": anyone who can connect)
  std::string control_group;   // may call start/stop too ("": anyone who can connect)
  int max_clients = 16;
  int max_line_bytes = 64 * 1024;
  double idle_timeout_s = 300;
  int max_pending_bytes = 1 << 20;
};

// The bus recording (config section [record]; docs/replay.md).
struct RecordSettings {
  bool enabled = false;
  int max_bytes = 64 << 20;     // a file is rotated at this size
  int files = 4;                // bus.log and bus.log.1 .. bus.log.(files-1)
  int buffer_bytes = 1 << 20;   // lines waiting for the writer thread at most (more: dropped)
};

// Default-constructed: the built-in defaults (the core's are DefaultCoreOptions()).
struct DaemonSettings {
  robot::CoreOptions core = robot::DefaultCoreOptions();  // every other section
  ApiSettings api;                                         // [api]
  drivers::GpioSettings gpio;  // [gpio]'s lines (its debounce_s is core.safety's)
  RecordSettings record;                                   // [record]
  std::string state_dir = "/var/lib/irslam";               // [state].dir: the saved map
  // [control].realtime_priority: SCHED_FIFO priority of the control loop's
  // thread, 0 = normal scheduling (daemon/realtime.h).
  int realtime_priority = 10;
};

}  // namespace irslam

#endif  // IRSLAM_DAEMON_DAEMON_SETTINGS_H_
