#include "daemon/config.h"

#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "proto/json_text.h"

namespace irslam {
namespace {

using nlohmann::json;

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

  void Num(const char* key, double* out, double lo, double hi) {
    const json* v = Find(key);
    if (v == nullptr) return;
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

void ReadRobot(const json& j, control::CoreOptions* o, std::string* e) {
  Section s(j, "robot", e);
  auto& g = o->slam.geometry;
  s.Num("wheel_base_m", &g.wheel_base_m, 0.05, 2.0);
  s.Num("wheel_radius_m", &g.wheel_radius_m, 0.005, 0.5);
  s.Num("counts_per_rev", &g.counts_per_rev, 1, 1e7);
  s.Num("radius_m", &g.radius_m, 0.05, 2.0);
  s.Num("max_wheel_speed_mps", &g.max_wheel_speed_mps, 0.01, 5.0);
  s.Finish();
}

void ReadSensors(const json& j, control::CoreOptions* o, std::string* e) {
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

void ReadController(const json& j, control::CoreOptions* o, std::string* e) {
  Section s(j, "controller", e);
  s.Num("timeout_s", &o->motor.timeout_s, 0.005, 10);
  s.Num("heartbeat_period_s", &o->heartbeat_period_s, 0.01, 10);
  s.Finish();
}

void ReadControl(const json& j, control::CoreOptions* o, std::string* e) {
  Section s(j, "control", e);
  s.Num("period_s", &o->period_s, 0.001, 1.0);
  s.Finish();
}

void ReadWallFollow(const json& j, control::CoreOptions* o, std::string* e) {
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

void ReadMission(const json& j, control::CoreOptions* o, std::string* e) {
  Section s(j, "mission", e);
  auto& m = o->mission;
  s.Num("max_time_s", &m.max_time_s, 1, 1e6);
  s.Num("progress_timeout_s", &m.progress_timeout_s, 1, 1e6);
  s.Num("loop_min_distance_m", &m.loop_min_distance_m, 0.1, 1000);
  s.Num("loop_close_radius_m", &m.loop_close_radius_m, 0.01, 10);
  s.Num("loop_close_angle_rad", &m.loop_close_angle_rad, 0.01, 3.2);
  s.Num("max_accel_mps2", &m.max_accel_mps2, 0.01, 20);
  s.Finish();
}

void ReadSlam(const json& j, control::CoreOptions* o, std::string* e) {
  Section s(j, "slam", e);
  s.Num("trajectory_period_s", &o->slam.trajectory_period_s, 0.01, 0.5);
  s.Num("var_per_m", &o->slam.motion_noise.var_per_m, 0, 1);
  s.Num("var_theta_per_rad", &o->slam.motion_noise.var_theta_per_rad, 0, 1);
  s.Num("var_theta_per_m", &o->slam.motion_noise.var_theta_per_m, 0, 1);
  s.Finish();
}

}  // namespace

bool ParseConfig(std::string_view text, control::CoreOptions* options, std::string* error) {
  error->clear();
  const std::optional<json> parsed = ParseJsonText(text, error);
  if (!parsed) {
    *error = "config: " + *error;
    return false;
  }
  const json& j = *parsed;
  control::CoreOptions o = *options;
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
  top.Finish();
  if (!error->empty()) return false;
  *options = o;
  return true;
}

bool LoadConfigFile(const std::string& path, control::CoreOptions* options, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    *error = "config: cannot read " + path;
    return false;
  }
  std::stringstream ss;
  ss << in.rdbuf();
  if (!ParseConfig(ss.str(), options, error)) {
    *error = path + ": " + *error;
    return false;
  }
  return true;
}

std::string DumpConfig(const control::CoreOptions& o) {
  json mounts = json::array();
  for (const auto& m : o.slam.mounts) mounts.push_back({m.x, m.y, m.theta});
  json table = json::array();
  for (const auto& [d, v] : o.ir.table) table.push_back({d, v});
  const auto& g = o.slam.geometry;
  const auto& w = o.wall;
  const auto& m = o.mission;
  json j = {
      {"robot", {{"wheel_base_m", g.wheel_base_m}, {"wheel_radius_m", g.wheel_radius_m},
                 {"counts_per_rev", g.counts_per_rev}, {"radius_m", g.radius_m},
                 {"max_wheel_speed_mps", g.max_wheel_speed_mps}}},
      {"sensors", {{"mounts", mounts}, {"adc_vref_v", o.ir.adc_vref_v},
                   {"adc_bits", o.ir.adc_bits}, {"table", table},
                   {"min_range_m", o.ir.min_range_m}, {"max_range_m", o.ir.max_range_m}}},
      {"controller", {{"timeout_s", o.motor.timeout_s},
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
                   {"loop_min_distance_m", m.loop_min_distance_m},
                   {"loop_close_radius_m", m.loop_close_radius_m},
                   {"loop_close_angle_rad", m.loop_close_angle_rad},
                   {"max_accel_mps2", m.max_accel_mps2}}},
      {"slam", {{"trajectory_period_s", o.slam.trajectory_period_s},
                {"var_per_m", o.slam.motion_noise.var_per_m},
                {"var_theta_per_rad", o.slam.motion_noise.var_theta_per_rad},
                {"var_theta_per_m", o.slam.motion_noise.var_theta_per_m}}},
  };
  return j.dump(2);
}

}  // namespace irslam
