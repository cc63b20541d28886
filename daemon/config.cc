#include "daemon/config.h"

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "io/file_io.h"
#include "io/json_text.h"

namespace irslam {
namespace {

using nlohmann::json;

// A config file is a few kB; anything much larger is not one.
constexpr size_t kMaxConfigBytes = 1 << 20;

// Reads keys of one JSON object, remembering which ones were used so unknown keys
// can be reported by name.
class Section {
 public:
  Section(const json& j, std::string path, std::string* error)
      : j_(j), path_(std::move(path)), error_(error) {
    if (!j_.is_object() && error_->empty()) {
      *error_ = "config: " + (path_.empty() ? std::string("the top level") : path_) + " must be an object";
    }
  }

  // out == nullptr: only marks the key as known (read elsewhere).
  void Num(const char* key, double* out, double lo, double hi) {
    const json* v = Find(key);
    if (v == nullptr || out == nullptr) return;
    if (!v->is_number()) return Fail(key, "must be a number");
    const double d = v->get<double>();
    if (!(d >= lo && d <= hi)) {
      std::ostringstream os;
      os << "must be in [" << lo << ", " << hi << "] (got " << d << ")";
      return Fail(key, os.str());
    }
    *out = d;
  }
  void Int(const char* key, int* out, int lo, int hi) {
    double d = *out;
    Num(key, &d, lo, hi);
    if (d != static_cast<int>(d)) return Fail(key, "must be an integer");
    *out = static_cast<int>(d);
  }
  // Returns the nested object (or null json if absent).
  const json* Sub(const char* key) {
    const json* v = Find(key);
    if (v != nullptr && !v->is_object()) {
      Fail(key, "must be an object");
      return nullptr;
    }
    return v;
  }
  const json* Array(const char* key) {
    const json* v = Find(key);
    if (v != nullptr && !v->is_array()) {
      Fail(key, "must be an array");
      return nullptr;
    }
    return v;
  }
  void Fail(const std::string& key, const std::string& what) {
    if (error_->empty()) *error_ = "config: " + Name(key) + " " + what;
  }
  void Finish() {
    if (!j_.is_object()) return;
    for (const auto& [k, v] : j_.items()) {
      if (!used_.count(k)) return Fail(k, "is not a known key");
    }
  }
  std::string Name(const std::string& key) const {
    if (path_.empty()) return key;
    if (key.empty()) return path_;
    return path_ + "." + key;
  }

 private:
  const json* Find(const char* key) {
    used_.insert(key);
    if (!j_.is_object()) return nullptr;
    auto it = j_.find(key);
    return it == j_.end() ? nullptr : &*it;
  }

  const json& j_;
  std::string path_;
  std::string* error_;
  std::set<std::string> used_;
};

void ReadRobot(const json& j, robot::CoreOptions* o, std::string* e) {
  Section s(j, "robot", e);
  auto& g = o->slam.geometry;
  s.Num("wheel_base_m", &g.wheel_base_m, 0.05, 2.0);
  s.Num("wheel_radius_m", &g.wheel_radius_m, 0.005, 0.5);
  s.Num("counts_per_rev", &g.counts_per_rev, 1, 1e7);
  s.Num("radius_m", &g.radius_m, 0.05, 2.0);
  s.Num("max_wheel_speed_mps", &g.max_wheel_speed_mps, 0.01, 5.0);
  s.Finish();
}

void ReadSensors(const json& j, robot::CoreOptions* o, std::string* e) {
  Section s(j, "sensors", e);
  if (const json* m = s.Array("mounts")) {
    if (m->size() != kNumIrSensors) {
      s.Fail("mounts", "must list exactly 7 sensors as [x_m, y_m, theta_rad]");
    } else {
      for (size_t i = 0; i < m->size(); ++i) {
        const json& p = (*m)[i];
        if (!p.is_array() || p.size() != 3 || !p[0].is_number() || !p[1].is_number() ||
            !p[2].is_number()) {
          s.Fail("mounts[" + std::to_string(i) + "]", "must be [x_m, y_m, theta_rad]");
          break;
        }
        o->slam.mounts[i] = {p[0].get<double>(), p[1].get<double>(), p[2].get<double>()};
      }
    }
  }
  auto& ir = o->ir;
  s.Num("adc_vref_v", &ir.adc_vref_v, 0.1, 24);
  s.Int("adc_bits", &ir.adc_bits, 8, 16);
  s.Num("min_range_m", &ir.min_range_m, 0.0, 10.0);
  s.Num("max_range_m", &ir.max_range_m, 0.0, 10.0);
  s.Num("plausible_min_v", &ir.plausible_min_v, 0.0, 10.0);
  s.Num("plausible_max_v", &ir.plausible_max_v, 0.0, 10.0);
  s.Int("stuck_samples", &ir.stuck_samples, 0, 100000);
  if (const json* t = s.Array("table")) {
    std::vector<std::pair<double, double>> table;
    for (size_t i = 0; i < t->size(); ++i) {
      const json& p = (*t)[i];
      if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number()) {
        s.Fail("table[" + std::to_string(i) + "]", "must be [distance_m, volts]");
        break;
      }
      table.emplace_back(p[0].get<double>(), p[1].get<double>());
    }
    ir.table = table;
  }
  s.Finish();
  if (e->empty()) {
    const std::string v = ir.Validate();
    if (!v.empty()) *e = "config: " + v;
  }
}

void ReadController(const json& j, robot::CoreOptions* o, std::string* e) {
  Section s(j, "controller", e);
  s.Num("timeout_s", &o->motor.timeout_s, 0.005, 10);
  s.Num("heartbeat_period_s", &o->heartbeat_period_s, 0.01, 10);
  s.Num("plausible_speed_factor", &o->motor.plausible_speed_factor, 0, 100);
  s.Finish();
}

void ReadControl(const json& j, robot::CoreOptions* o, std::string* e) {
  Section s(j, "control", e);
  s.Num("period_s", &o->period_s, 0.001, 1.0);
  s.Finish();
}

void ReadWallFollow(const json& j, robot::CoreOptions* o, std::string* e) {
  Section s(j, "wall_follow", e);
  auto& w = o->wall;
  s.Num("follow_distance_m", &w.follow_distance_m, 0.1, 2.0);
  s.Num("cruise_speed_mps", &w.cruise_speed_mps, 0.01, 2.0);
  s.Num("front_stop_m", &w.front_stop_m, 0.1, 2.0);
  s.Num("front_slow_m", &w.front_slow_m, 0.1, 3.0);
  s.Num("k_distance", &w.k_distance, 0, 100);
  s.Num("k_angle", &w.k_angle, 0, 100);
  s.Num("max_turn_rate_rad_s", &w.max_turn_rate_rad_s, 0.05, 10);
  s.Num("turn_rate_rad_s", &w.turn_rate_rad_s, 0.05, 10);
  s.Num("lost_wall_margin_m", &w.lost_wall_margin_m, 0.05, 2.0);
  s.Num("outer_arc_speed_mps", &w.outer_arc_speed_mps, 0.01, 2.0);
  s.Num("backoff_speed_mps", &w.backoff_speed_mps, 0.01, 1.0);
  s.Num("backoff_time_s", &w.backoff_time_s, 0.0, 10.0);
  s.Num("backoff_turn_rad", &w.backoff_turn_rad, 0.0, 3.2);
  s.Finish();
}

void ReadBool(const json& j, const char* key, bool* out, Section* s) {
  if (!j.is_object() || !j.contains(key)) return;
  if (!j.at(key).is_boolean()) return s->Fail(key, "must be true or false");
  *out = j.at(key).get<bool>();
}

void ReadMission(const json& j, robot::CoreOptions* o, std::string* e) {
  Section s(j, "mission", e);
  auto& m = o->mission;
  s.Num("max_time_s", &m.max_time_s, 1, 1e6);
  s.Num("progress_timeout_s", &m.progress_timeout_s, 1, 1e6);
  s.Num("loop_min_distance_m", &m.loop.loop_min_distance_m, 0.1, 1000);
  s.Num("loop_close_radius_m", &m.loop.loop_close_radius_m, 0.01, 10);
  s.Num("loop_close_angle_rad", &m.loop.loop_close_angle_rad, 0.01, 3.2);
  s.Num("max_accel_mps2", &m.max_accel_mps2, 0.01, 20);
  s.Int("wall_follow_loops", &m.wall_follow_loops, 1, 100);
  ReadBool(j, "explore", &m.explore, &s);
  s.Num("explore", nullptr, 0, 0);
  s.Finish();
}


void ReadString(const json& j, const char* key, std::string* out, Section* s) {
  if (!j.is_object() || !j.contains(key)) return;
  if (!j.at(key).is_string()) return s->Fail(key, "must be a string");
  *out = j.at(key).get<std::string>();
}

void ReadApi(const json& j, robot::CoreOptions* o, std::string* e) {
  Section s(j, "api", e);
  auto& a = o->api;
  for (const auto& [key, out] : {std::pair<const char*, std::string*>{"socket_group", &a.socket_group},
                                 {"read_group", &a.read_group},
                                 {"control_group", &a.control_group}}) {
    ReadString(j, key, out, &s);
    s.Num(key, nullptr, 0, 0);
  }
  s.Int("max_clients", &a.max_clients, 1, 1024);
  s.Int("max_line_bytes", &a.max_line_bytes, 256, 16 * 1024 * 1024);
  s.Num("idle_timeout_s", &a.idle_timeout_s, 0.1, 1e6);
  s.Int("max_pending_bytes", &a.max_pending_bytes, 4096, 256 * 1024 * 1024);
  s.Finish();
}

void ReadGpioLine(const char* key, drivers::GpioLineSpec* out, Section* parent, std::string* e) {
  const json* sub = parent->Sub(key);
  if (sub == nullptr) return;
  Section s(*sub, parent->Name(key), e);
  ReadString(*sub, "chip", &out->chip, &s);
  s.Num("chip", nullptr, 0, 0);
  if (sub->is_object() && sub->contains("line")) {
    const json& l = sub->at("line");
    if (l.is_number_unsigned()) {
      out->line = std::to_string(l.get<uint64_t>());
    } else if (l.is_string()) {
      out->line = l.get<std::string>();
    } else {
      s.Fail("line", "must be a line name or an offset");
    }
  }
  s.Num("line", nullptr, 0, 0);
  ReadBool(*sub, "active_low", &out->active_low, &s);
  s.Num("active_low", nullptr, 0, 0);
  if (!out->chip.empty() && out->line.empty()) s.Fail("line", "must be given when chip is");
  s.Finish();
}

void ReadState(const json& j, robot::CoreOptions* o, std::string* e) {
  Section s(j, "state", e);
  ReadString(j, "dir", &o->state_dir, &s);
  s.Num("dir", nullptr, 0, 0);
  if (o->state_dir.empty()) s.Fail("dir", "must not be empty");
  s.Finish();
}

void ReadGpio(const json& j, robot::CoreOptions* o, std::string* e) {
  Section s(j, "gpio", e);
  auto& g = o->gpio;
  ReadGpioLine("estop", &g.estop, &s, e);
  ReadGpioLine("bumper_left", &g.bumper_left, &s, e);
  ReadGpioLine("bumper_right", &g.bumper_right, &s, e);
  ReadGpioLine("motor_enable", &g.motor_enable, &s, e);
  ReadGpioLine("status_led", &g.status_led, &s, e);
  s.Num("debounce_s", &g.debounce_s, 0, 1);
  s.Finish();
}

void ReadExploration(const json& j, robot::CoreOptions* o, std::string* e) {
  Section s(j, "exploration", e);
  auto& x = o->explore;
  s.Num("clearance_m", &x.go_to.clearance_m, 0, 1);
  s.Num("goal_tolerance_m", &x.go_to.goal_tolerance_m, 0.01, 1);
  s.Num("heading_tolerance_rad", &x.go_to.heading_tolerance_rad, 0.01, 1);
  s.Num("cruise_speed_mps", &x.go_to.cruise_speed_mps, 0.01, 2);
  s.Num("lookahead_m", &x.go_to.lookahead_m, 0.05, 2);
  s.Num("k_heading", &x.go_to.k_heading, 0.1, 20);
  s.Num("replan_period_s", &x.go_to.replan_period_s, 0.1, 60);
  s.Num("front_stop_m", &x.go_to.front_stop_m, 0.1, 2);
  s.Num("go_to_timeout_s", &x.go_to.go_to_timeout_s, 1, 3600);
  s.Num("contour_timeout_s", &x.contour.contour_timeout_s, 1, 3600);
  s.Num("contour_leave_m", &x.contour.contour_leave_m, 0.05, 10);
  s.Int("contour_loops", &x.contour.contour_loops, 1, 10);
  s.Num("go_to_stuck_s", &x.go_to.go_to_stuck_s, 1, 3600);
  ReadBool(j, "survey_centre", &x.survey.survey_centre, &s);
  s.Num("survey_centre", nullptr, 0, 0);
  s.Int("max_surveys", &x.survey.max_surveys, 0, 100);
  s.Num("survey_range_m", &x.survey.survey_range_m, 0.1, 5);
  s.Num("survey_min_unseen_m2", &x.survey.survey_min_unseen_m2, 0, 100);
  s.Finish();
}

void ReadModel(const json& j, robot::CoreOptions* o, std::string* e) {
  Section s(j, "model", e);
  auto& m = o->model;
  s.Num("axis_tolerance_rad", &m.axis_tolerance_rad, 0.001, 0.7);
  s.Num("collinear_m", &m.collinear_m, 0.001, 1);
  s.Num("corner_m", &m.corner_m, 0.01, 2);
  s.Num("wall_contact_m", &m.wall_contact_m, 0.01, 2);
  s.Num("wall_reach_m", &m.wall_reach_m, 0, 2);
  s.Finish();
}


void ReadSlam(const json& j, robot::CoreOptions* o, std::string* e) {
  Section s(j, "slam", e);
  s.Num("trajectory_period_s", &o->slam.trajectory_period_s, 0.01, 0.5);
  s.Num("var_per_m", &o->slam.motion_noise.var_per_m, 0, 1);
  s.Num("var_theta_per_rad", &o->slam.motion_noise.var_theta_per_rad, 0, 1);
  s.Num("var_theta_per_m", &o->slam.motion_noise.var_theta_per_m, 0, 1);
  static const json kEmpty = json::object();
  const json* pj = s.Sub("pds");
  {
    Section p(pj ? *pj : kEmpty, "slam.pds", e);
    auto& d = o->slam.pds;
    p.Num("min_step_m", &d.min_step_m, 0, 1);
    p.Num("min_turn_rad", &d.min_turn_rad, 0, 1);
    p.Num("window_m", &d.window_m, 0.05, 10);
    p.Num("window_rad", &d.window_rad, 0.05, 10);
    p.Num("max_range_m", &d.max_range_m, 0.1, 10);
    p.Finish();
  }
  const json* xj = s.Sub("extraction");
  {
    Section x(xj ? *xj : kEmpty, "slam.extraction", e);
    auto& d = o->slam.extraction;
    x.Num("gravity_radius_m", &d.gravity_radius_m, 0, 1);
    x.Int("gravity_max_points", &d.gravity_max_points, 1, 100);
    x.Num("cluster_gap_m", &d.cluster_gap_m, 0.005, 2);
    x.Int("min_points", &d.min_points, 2, 10000);
    x.Num("min_length_m", &d.min_length_m, 0.01, 10);
    x.Num("split_threshold_m", &d.split_threshold_m, 0.001, 1);
    x.Num("max_fit_rms_m", &d.max_fit_rms_m, 0.0001, 1);
    x.Num("hough_rho_window_m", &d.hough_rho_window_m, 0.001, 1);
    x.Num("hough_rho_res_m", &d.hough_rho_res_m, 0.0001, 0.5);
    x.Num("hough_theta_window_rad", &d.hough_theta_window_rad, 0.001, 1);
    x.Num("hough_theta_res_rad", &d.hough_theta_res_rad, 0.0001, 0.5);
    x.Num("weight_length", &d.weight_length, 0, 1e6);
    x.Num("weight_rho", &d.weight_rho, 0, 1e9);
    x.Num("weight_theta", &d.weight_theta, 0, 1e9);
    x.Num("max_uncertainty", &d.max_uncertainty, 0, 1e9);
    x.Finish();
  }
  const json* aj = s.Sub("association");
  {
    Section a(aj ? *aj : kEmpty, "slam.association", e);
    auto& d = o->slam.association;
    a.Num("weight_rho", &d.weight_rho, 0, 1);
    a.Num("weight_theta", &d.weight_theta, 0, 1);
    a.Num("max_dh", &d.max_dh, 0, 10);
    a.Num("angle_tolerance_rad", &d.angle_tolerance_rad, 0, 0.78);
    a.Num("constraint_sigma_rad", &d.constraint_sigma_rad, 1e-9, 1);
    a.Num("collinear_sigma_m", &d.collinear_sigma_m, 1e-9, 1);
    a.Num("collinear_max_m", &d.collinear_max_m, 0, 1);
    a.Num("collinear_min_length_m", &d.collinear_min_length_m, 0, 100);
    a.Num("measurement_cov_scale", &d.measurement_cov_scale, 1e-6, 1e6);
    a.Num("max_mahalanobis2", &d.max_mahalanobis2, 0.1, 1e9);
    ReadBool(aj ? *aj : kEmpty, "use_constraints", &d.use_constraints, &a);
    a.Num("use_constraints", nullptr, 0, 0);
    ReadBool(aj ? *aj : kEmpty, "pin_first_line", &d.pin_first_line, &a);
    a.Num("pin_first_line", nullptr, 0, 0);
    a.Finish();
    if (e->empty() && std::abs(d.weight_rho + d.weight_theta - 1) > 1e-9) {
      *e = "config: slam.association.weight_rho + weight_theta must be 1";
    }
  }
  s.Finish();
}

}  // namespace

bool ParseConfig(std::string_view text, robot::CoreOptions* options, std::string* error) {
  error->clear();
  const std::optional<json> parsed = ParseJsonText(text, error);
  if (!parsed) {
    *error = "config: " + *error;
    return false;
  }
  const json& j = *parsed;
  robot::CoreOptions o = *options;
  Section top(j, "", error);
  static const json kEmpty = json::object();
  const auto sub = [&](const char* k) {
    const json* p = top.Sub(k);
    return p ? *p : kEmpty;
  };
  ReadRobot(sub("robot"), &o, error);
  ReadSensors(sub("sensors"), &o, error);
  ReadController(sub("controller"), &o, error);
  ReadControl(sub("control"), &o, error);
  ReadWallFollow(sub("wall_follow"), &o, error);
  ReadMission(sub("mission"), &o, error);
  ReadSlam(sub("slam"), &o, error);
  ReadExploration(sub("exploration"), &o, error);
  ReadModel(sub("model"), &o, error);
  ReadApi(sub("api"), &o, error);
  ReadGpio(sub("gpio"), &o, error);
  ReadState(sub("state"), &o, error);
  top.Finish();
  if (!error->empty()) return false;
  *options = o;
  return true;
}

bool LoadConfigFile(const std::string& path, robot::CoreOptions* options, std::string* error) {
  std::string text;
  if (!ReadRegularFile(path, kMaxConfigBytes, &text, error)) {
    *error = "config: " + *error;
    return false;
  }
  if (!ParseConfig(text, options, error)) {
    *error = path + ": " + *error;
    return false;
  }
  return true;
}

std::string DumpConfig(const robot::CoreOptions& o) {
  json mounts = json::array();
  for (const auto& m : o.slam.mounts) mounts.push_back({m.x, m.y, m.theta});
  json table = json::array();
  for (const auto& [d, v] : o.ir.table) table.push_back({d, v});
  const auto& g = o.slam.geometry;
  const auto& w = o.wall;
  const auto& m = o.mission;
  const auto& p = o.slam.pds;
  const auto& x = o.slam.extraction;
  const auto& a = o.slam.association;
  const auto& ex = o.explore;
  const auto& mo = o.model;
  const auto line = [](const drivers::GpioLineSpec& l) {
    return json{{"chip", l.chip}, {"line", l.line}, {"active_low", l.active_low}};
  };
  const auto& gp = o.gpio;
  json j = {
      {"state", {{"dir", o.state_dir}}},
      {"gpio", {{"estop", line(gp.estop)}, {"bumper_left", line(gp.bumper_left)},
                {"bumper_right", line(gp.bumper_right)}, {"motor_enable", line(gp.motor_enable)},
                {"status_led", line(gp.status_led)}, {"debounce_s", gp.debounce_s}}},
      {"api", {{"socket_group", o.api.socket_group}, {"read_group", o.api.read_group},
               {"control_group", o.api.control_group}, {"max_clients", o.api.max_clients},
               {"max_line_bytes", o.api.max_line_bytes}, {"idle_timeout_s", o.api.idle_timeout_s},
               {"max_pending_bytes", o.api.max_pending_bytes}}},
      {"exploration", {{"clearance_m", ex.go_to.clearance_m}, {"goal_tolerance_m", ex.go_to.goal_tolerance_m},
                       {"heading_tolerance_rad", ex.go_to.heading_tolerance_rad},
                       {"cruise_speed_mps", ex.go_to.cruise_speed_mps}, {"lookahead_m", ex.go_to.lookahead_m},
                       {"k_heading", ex.go_to.k_heading}, {"replan_period_s", ex.go_to.replan_period_s},
                       {"front_stop_m", ex.go_to.front_stop_m}, {"go_to_timeout_s", ex.go_to.go_to_timeout_s},
                       {"contour_timeout_s", ex.contour.contour_timeout_s},
                       {"contour_leave_m", ex.contour.contour_leave_m},
                       {"contour_loops", ex.contour.contour_loops},
                       {"go_to_stuck_s", ex.go_to.go_to_stuck_s},
                       {"survey_centre", ex.survey.survey_centre},
                       {"max_surveys", ex.survey.max_surveys},
                       {"survey_range_m", ex.survey.survey_range_m},
                       {"survey_min_unseen_m2", ex.survey.survey_min_unseen_m2}}},
      {"model", {{"axis_tolerance_rad", mo.axis_tolerance_rad}, {"collinear_m", mo.collinear_m},
                 {"corner_m", mo.corner_m}, {"wall_contact_m", mo.wall_contact_m}, {"wall_reach_m", mo.wall_reach_m}}},
      {"robot", {{"wheel_base_m", g.wheel_base_m}, {"wheel_radius_m", g.wheel_radius_m},
                 {"counts_per_rev", g.counts_per_rev}, {"radius_m", g.radius_m},
                 {"max_wheel_speed_mps", g.max_wheel_speed_mps}}},
      {"sensors", {{"mounts", mounts}, {"adc_vref_v", o.ir.adc_vref_v},
                   {"adc_bits", o.ir.adc_bits}, {"table", table},
                   {"min_range_m", o.ir.min_range_m}, {"max_range_m", o.ir.max_range_m},
                   {"plausible_min_v", o.ir.plausible_min_v}, {"plausible_max_v", o.ir.plausible_max_v},
                   {"stuck_samples", o.ir.stuck_samples}}},
      {"controller", {{"timeout_s", o.motor.timeout_s},
                      {"plausible_speed_factor", o.motor.plausible_speed_factor},
                      {"heartbeat_period_s", o.heartbeat_period_s}}},
      {"control", {{"period_s", o.period_s}}},
      {"wall_follow", {{"follow_distance_m", w.follow_distance_m},
                       {"cruise_speed_mps", w.cruise_speed_mps},
                       {"front_stop_m", w.front_stop_m}, {"front_slow_m", w.front_slow_m},
                       {"k_distance", w.k_distance}, {"k_angle", w.k_angle},
                       {"max_turn_rate_rad_s", w.max_turn_rate_rad_s},
                       {"turn_rate_rad_s", w.turn_rate_rad_s},
                       {"lost_wall_margin_m", w.lost_wall_margin_m},
                       {"outer_arc_speed_mps", w.outer_arc_speed_mps},
                       {"backoff_speed_mps", w.backoff_speed_mps},
                       {"backoff_time_s", w.backoff_time_s},
                       {"backoff_turn_rad", w.backoff_turn_rad}}},
      {"mission", {{"max_time_s", m.max_time_s}, {"progress_timeout_s", m.progress_timeout_s},
                   {"loop_min_distance_m", m.loop.loop_min_distance_m},
                   {"loop_close_radius_m", m.loop.loop_close_radius_m},
                   {"loop_close_angle_rad", m.loop.loop_close_angle_rad},
                   {"max_accel_mps2", m.max_accel_mps2},
                   {"wall_follow_loops", m.wall_follow_loops},
                   {"explore", m.explore}}},
      {"slam", {{"trajectory_period_s", o.slam.trajectory_period_s},
                {"var_per_m", o.slam.motion_noise.var_per_m},
                {"var_theta_per_rad", o.slam.motion_noise.var_theta_per_rad},
                {"var_theta_per_m", o.slam.motion_noise.var_theta_per_m},
                {"pds", {{"min_step_m", p.min_step_m}, {"min_turn_rad", p.min_turn_rad},
                         {"window_m", p.window_m}, {"window_rad", p.window_rad},
                         {"max_range_m", p.max_range_m}}},
                {"extraction", {{"gravity_radius_m", x.gravity_radius_m},
                                {"gravity_max_points", x.gravity_max_points},
                                {"cluster_gap_m", x.cluster_gap_m}, {"min_points", x.min_points},
                                {"min_length_m", x.min_length_m},
                                {"split_threshold_m", x.split_threshold_m},
                                {"max_fit_rms_m", x.max_fit_rms_m},
                                {"hough_rho_window_m", x.hough_rho_window_m},
                                {"hough_rho_res_m", x.hough_rho_res_m},
                                {"hough_theta_window_rad", x.hough_theta_window_rad},
                                {"hough_theta_res_rad", x.hough_theta_res_rad},
                                {"weight_length", x.weight_length}, {"weight_rho", x.weight_rho},
                                {"weight_theta", x.weight_theta},
                                {"max_uncertainty", x.max_uncertainty}}},
                {"association", {{"weight_rho", a.weight_rho}, {"weight_theta", a.weight_theta},
                                 {"max_dh", a.max_dh},
                                 {"angle_tolerance_rad", a.angle_tolerance_rad},
                                 {"constraint_sigma_rad", a.constraint_sigma_rad},
                                 {"collinear_sigma_m", a.collinear_sigma_m},
                                 {"collinear_max_m", a.collinear_max_m},
                                 {"collinear_min_length_m", a.collinear_min_length_m},
                                 {"measurement_cov_scale", a.measurement_cov_scale},
                                 {"max_mahalanobis2", a.max_mahalanobis2},
                                 {"use_constraints", a.use_constraints},
                                 {"pin_first_line", a.pin_first_line}}}}},
  };
  return j.dump(2);
}

}  // namespace irslam
