#include "daemon/config_schema.h"

#include <cmath>
#include <string>
#include <vector>

#include "io/json_text.h"

namespace irslam::config {
namespace {

using nlohmann::json;

// The core's own loose settings (robot::CoreOptions members outside a component).
options::Table<robot::CoreOptions> ControlPeriodKeys() {
  static constexpr options::Key<robot::CoreOptions> kKeys[] = {
      {"period_s", &robot::CoreOptions::period_s, 0.001, 1.0, "s", "control loop period (robot time)"},
  };
  return kKeys;
}

options::Table<robot::CoreOptions> HeartbeatKeys() {
  static constexpr options::Key<robot::CoreOptions> kKeys[] = {
      {"heartbeat_period_s", &robot::CoreOptions::heartbeat_period_s, 0.01, 10, "s",
       "DAEMON_HEARTBEAT period"},
  };
  return kKeys;
}

// The daemon's own settings.
options::Table<DaemonSettings> StateKeys() {
  static constexpr options::Key<DaemonSettings> kKeys[] = {
      {"dir", &DaemonSettings::state_dir, 0, 0, "",
       "the map is saved here (map.json; systemd StateDirectory=irslam)"},
  };
  return kKeys;
}

options::Table<DaemonSettings> LoopThreadKeys() {
  static constexpr options::Key<DaemonSettings> kKeys[] = {
      {"realtime_priority", &DaemonSettings::realtime_priority, 0, 99, "",
       "irslamd only: SCHED_FIFO priority of the control loop's thread, 0 = normal scheduling (needs "
       "LimitRTPRIO= or CAP_SYS_NICE; refused: normal scheduling, logged)"},
  };
  return kKeys;
}

options::Table<ApiSettings> ApiKeys() {
  using A = ApiSettings;
  static constexpr options::Key<A> kKeys[] = {
      {"socket_group", &A::socket_group, 0, 0, "", "chgrp the socket to this group (\"\": the daemon's group)"},
      {"read_group", &A::read_group, 0, 0, "", "may call status/map/subscribe (\"\": anyone who can connect)"},
      {"control_group", &A::control_group, 0, 0, "", "may call start/stop too (\"\": anyone who can connect)"},
      {"max_clients", &A::max_clients, 1, 1024, "", "connected clients at most"},
      {"max_line_bytes", &A::max_line_bytes, 256, 1024 * 1024, "bytes",
       "a longer request line: error, connection closed"},
      {"idle_timeout_s", &A::idle_timeout_s, 0.1, 1e6, "s", "clients that send nothing (and are not subscribed)"},
      {"max_pending_bytes", &A::max_pending_bytes, 4096, 256 * 1024 * 1024, "bytes",
       "unread output beyond this: the client is dropped"},
  };
  return kKeys;
}

options::Table<RecordSettings> RecordKeys() {
  using R = RecordSettings;
  static constexpr options::Key<R> kKeys[] = {
      {"enabled", &R::enabled, 0, 0, "", "record the bus to STATE_DIR/bus.log (candump -L; irslam-replay)"},
      {"max_bytes", &R::max_bytes, 65536, 2147483647, "bytes", "a log file is rotated at this size"},
      {"files", &R::files, 1, 100, "", "files kept: bus.log and bus.log.1 .. bus.log.(files-1)"},
      {"buffer_bytes", &R::buffer_bytes, 4096, 64 * 1024 * 1024, "bytes",
       "lines waiting for the writer at most (more are dropped and counted)"},
  };
  return kKeys;
}

// "[i]what". Appended, not "[" + std::string: GCC 12 at -O3 reports a false
// -Wrestrict for a literal + std::string (GCC PR 105329), which fails a Release
// build with warnings as errors.
std::string Indexed(size_t i, const char* what) {
  std::string s = "[";
  s += std::to_string(i);
  s += what;
  return s;
}

// "" or "KEY what" for a value that is not [x_m, y_m, theta_rad] x 7.
std::string ReadMounts(const json& m, robot::CoreOptions* o) {
  if (!m.is_array()) return " must be an array";
  if (m.size() != kNumIrSensors) return " must list exactly 7 sensors as [x_m, y_m, theta_rad]";
  for (size_t i = 0; i < m.size(); ++i) {
    const json& p = m[i];
    if (!p.is_array() || p.size() != 3 || !p[0].is_number() || !p[1].is_number() || !p[2].is_number()) {
      return Indexed(i, "] must be [x_m, y_m, theta_rad]");
    }
    o->slam.mounts[i] = {p[0].get<double>(), p[1].get<double>(), p[2].get<double>()};
  }
  return "";
}

std::string ReadIrTable(const json& t, robot::CoreOptions* o) {
  if (!t.is_array()) return " must be an array";
  std::vector<std::pair<double, double>> table;
  for (size_t i = 0; i < t.size(); ++i) {
    const json& p = t[i];
    if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number()) {
      return Indexed(i, "] must be [distance_m, volts]");
    }
    table.emplace_back(p[0].get<double>(), p[1].get<double>());
  }
  o->ir.table = table;
  return "";
}

std::string ReadGpioLine(const json& j, drivers::GpioLineSpec* out) {
  if (!j.is_object()) return " must be an object";
  for (const auto& [k, v] : j.items()) {
    if (k == "chip") {
      if (!v.is_string()) return ".chip must be a string";
      out->chip = v.get<std::string>();
    } else if (k == "line") {
      if (v.is_number_unsigned()) {
        out->line = std::to_string(v.get<uint64_t>());
      } else if (v.is_string()) {
        out->line = v.get<std::string>();
      } else {
        return ".line must be a line name or an offset";
      }
    } else if (k == "active_low") {
      if (!v.is_boolean()) return ".active_low must be true or false";
      out->active_low = v.get<bool>();
    } else {
      return std::string(".").append(OneLine(k)).append(" is not a known key");
    }
  }
  if (!out->chip.empty() && out->line.empty()) return ".line must be given when chip is";
  return "";
}

json DumpGpioLine(const drivers::GpioLineSpec& l) {
  return {{"chip", l.chip}, {"line", l.line}, {"active_low", l.active_low}};
}

// [gpio]: the lines are the daemon's, the debounce time the core's.
void WalkGpio(DaemonSettings* s, Visitor* v) {
  v->Section("gpio", "optional safety lines (libgpiod; docs/gpio.md). Each line: \"chip\" = label, name "
                     "(gpiochip0), path or number (\"\": not fitted), \"line\" = line name or offset, "
                     "\"active_low\" = pressed/on is the low level");
  auto& g = s->gpio;
  const struct {
    std::string_view name, doc;
    drivers::GpioLineSpec* line;
  } lines[] = {{"estop", "input: emergency stop", &g.estop},
               {"bumper_left", "input: left bumper", &g.bumper_left},
               {"bumper_right", "input: right bumper", &g.bumper_right},
               {"motor_enable", "output: motor-driver enable", &g.motor_enable},
               {"status_led", "output: status LED", &g.status_led}};
  for (const auto& l : lines) {
    drivers::GpioLineSpec* spec = l.line;
    v->Custom({l.name, l.doc, [spec](const json& j) { return ReadGpioLine(j, spec); },
               [spec] { return DumpGpioLine(*spec); }});
  }
  v->Keys(&s->core.safety, control::SafetyKeys());
  v->End();
}

void WalkSensors(robot::CoreOptions* o, Visitor* v) {
  v->Section("sensors", "");
  v->Custom({"mounts",
             "seven IR sensors [x_m, y_m, theta_rad] in the robot frame (x forward, y left), ordered right "
             "(-90 deg) to left (+90 deg); sensor 0 must look right and 3 straight ahead",
             [o](const json& j) { return ReadMounts(j, o); },
             [o] {
               json mounts = json::array();
               for (const auto& m : o->slam.mounts) mounts.push_back({m.x, m.y, m.theta});
               return mounts;
             }});
  v->Custom({"table", "Sharp GP2Y0A02-like output: [distance_m, volts] pairs, interpolated",
             [o](const json& j) { return ReadIrTable(j, o); },
             [o] {
               json table = json::array();
               for (const auto& [d, volts] : o->ir.table) table.push_back({d, volts});
               return table;
             }});
  v->Keys(&o->ir, drivers::IrCalibrationKeys());
  v->End();
}

void WalkSlam(robot::CoreOptions* o, Visitor* v) {
  v->Section("slam", "");
  v->Keys(&o->slam, slam::SlamKeys());
  v->Keys(&o->slam.motion_noise, slam::MotionNoiseKeys());
  v->Section("pds", "pseudo dense scan (paper section 3.1)");
  v->Keys(&o->slam.pds, slam::PdsKeys());
  v->End();
  v->Section("extraction", "multi-level filter (paper sections 3.1-3.5)");
  v->Keys(&o->slam.extraction, slam::ExtractionKeys());
  v->End();
  v->Section("association", "constrained EKF (paper section 4)");
  v->Keys(&o->slam.association, slam::AssociationKeys());
  v->End();
  v->Section("calibration", "odometry self-calibration: wheel radius and track width scale factors in the EKF");
  v->Keys(&o->slam.calibration, slam::CalibrationKeys());
  v->End();
  v->Section("resume", "continuing in a saved map: the relocalised pose's and the saved lines' uncertainty");
  v->Keys(&o->slam.resume, slam::ResumeKeys());
  v->End();
  v->End();
}

}  // namespace

void WalkConfig(DaemonSettings* s, Visitor* v) {
  v->Section("api", "the control socket (irslamd only)");
  v->Keys(&s->api, ApiKeys());
  v->End();
  v->Section("state", "");
  v->Keys(s, StateKeys());
  v->End();
  v->Section("record", "the daemon's own bus recording (irslamd only; applies at restart)");
  v->Keys(&s->record, RecordKeys());
  v->End();
  WalkGpio(s, v);
  // The core's sections.
  robot::CoreOptions* o = &s->core;
  v->Section("robot", "");
  v->Keys(&o->slam.geometry, RobotGeometryKeys());
  v->End();
  WalkSensors(o, v);
  v->Section("controller", "");
  v->Keys(&o->motor, drivers::MotorClientKeys());
  v->Keys(o, HeartbeatKeys());
  v->End();
  v->Section("control", "");
  v->Keys(o, ControlPeriodKeys());
  v->Keys(s, LoopThreadKeys());
  v->End();
  v->Section("wall_follow", "following the wall on the right (paper section 5)");
  v->Keys(&o->wall, control::WallFollowerKeys());
  v->End();
  v->Section("mission", "");
  v->Keys(&o->mission, control::MissionKeys());
  v->Keys(&o->mission.loop, control::LoopKeys());
  v->Keys(&o->mission.bump, control::BumpMemoryKeys());
  v->Keys(&o->mission.pen, control::PenKeys());
  v->End();
  v->Section("cleaning", "coverage planning and cleaning (mission.mode = \"clean\"; docs/cleaning.md)");
  v->Keys(&o->mission.cleaning, control::CleaningKeys());
  v->End();
  v->Section("relocalize", "relocalisation in the saved map at start, and the map's agreement after (docs/relocalization.md)");
  v->Keys(&o->mission.relocalize.search, slam::RelocalizeKeys());
  v->Keys(&o->mission.relocalize, control::RelocalizeKeys());
  v->Keys(&o->mission.relocalize.changes, control::MapChangeKeys());
  v->End();
  v->Section("model", "the room and furniture from the line map (paper section 5)");
  v->Keys(&o->model, control::ModelKeys());
  v->End();
  v->Section("exploration", "go to P1, contour following, surveys");
  v->Keys(&o->explore.go_to, control::GoToKeys());
  v->Keys(&o->explore.go_to.planner, control::PlannerKeys());
  v->Keys(&o->explore.contour, control::ContourKeys());
  v->Keys(&o->explore.survey, control::SurveyKeys());
  v->End();
  WalkSlam(o, v);
}

std::string CheckConfig(const DaemonSettings& s) {
  if (s.state_dir.empty()) return "state.dir must not be empty";
  const robot::CoreOptions& o = s.core;
  if (o.mission.mode != "explore" && o.mission.mode != "clean")
    return "mission.mode must be \"explore\" or \"clean\" (got \"" + o.mission.mode + "\")";
  const std::string ir = o.ir.Validate();
  if (!ir.empty()) return ir;
  const auto& a = o.slam.association;
  if (std::abs(a.weight_rho + a.weight_theta - 1) > 1e-9) {
    return "slam.association.weight_rho + weight_theta must be 1";
  }
  return "";
}

}  // namespace irslam::config
