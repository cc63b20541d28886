#include "sim/world.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "io/file_io.h"
#include "io/json_text.h"

namespace irslam::sim {
namespace {

// A world file is a few kB (a generated one with clutter some tens of kB).
constexpr size_t kMaxWorldBytes = 4 << 20;

using nlohmann::json;

bool ReadNumbers(const json& j, size_t n, std::vector<double>* out) {
  if (!j.is_array() || j.size() != n) return false;
  out->clear();
  for (const auto& v : j) {
    if (!v.is_number()) return false;
    out->push_back(v.get<double>());
  }
  return std::all_of(out->begin(), out->end(), [](double d) { return std::isfinite(d); });
}

}  // namespace

std::vector<Segment> World::Segments() const {
  std::vector<Segment> s;
  for (size_t i = 0; i < outline.size(); ++i) {
    s.push_back({outline[i], outline[(i + 1) % outline.size()]});
  }
  for (const Box& b : objects) {
    s.push_back({{b.xmin, b.ymin}, {b.xmax, b.ymin}});
    s.push_back({{b.xmax, b.ymin}, {b.xmax, b.ymax}});
    s.push_back({{b.xmax, b.ymax}, {b.xmin, b.ymax}});
    s.push_back({{b.xmin, b.ymax}, {b.xmin, b.ymin}});
  }
  return s;
}

Box World::Bounds() const {
  Box b{1e9, 1e9, -1e9, -1e9};
  for (const Vec2& p : outline) {
    b.xmin = std::min(b.xmin, p.x);
    b.ymin = std::min(b.ymin, p.y);
    b.xmax = std::max(b.xmax, p.x);
    b.ymax = std::max(b.ymax, p.y);
  }
  return b;
}

std::optional<World> ParseWorld(std::string_view text, std::string* error) {
  const std::optional<json> parsed = ParseJsonText(text, error);
  if (!parsed) {
    *error = "world: " + *error;
    return std::nullopt;
  }
  const json& j = *parsed;
  if (!j.is_object()) {
    *error = "world: the top level must be an object";
    return std::nullopt;
  }
  World w;
  std::vector<double> v;
  if (j.contains("name")) {
    if (!j.at("name").is_string()) {
      *error = "world: \"name\" must be a string";
      return std::nullopt;
    }
    w.name = j["name"].get<std::string>();
  }
  if (j.contains("outline")) {
    const json& o = j["outline"];
    if (!o.is_array() || o.size() < 4) {
      *error = "world: \"outline\" must be a closed polygon of at least 4 [x, y] points";
      return std::nullopt;
    }
    for (size_t i = 0; i < o.size(); ++i) {
      if (!ReadNumbers(o[i], 2, &v)) {
        *error = "world: \"outline\"[" + std::to_string(i) + "] must be [x, y]";
        return std::nullopt;
      }
      w.outline.push_back({v[0], v[1]});
    }
    for (size_t i = 0; i < w.outline.size(); ++i) {
      const Vec2 a = w.outline[i], b = w.outline[(i + 1) % w.outline.size()];
      if (a.x != b.x && a.y != b.y) {
        *error = "world: \"outline\" edge " + std::to_string(i) + " is not axis-aligned";
        return std::nullopt;
      }
    }
  } else {
    if (!j.contains("room") || !ReadNumbers(j["room"], 2, &v) || v[0] <= 0.5 || v[1] <= 0.5) {
      *error = "world: \"room\" must be [width, height] in metres (each > 0.5)";
      return std::nullopt;
    }
    w.outline = {{0, 0}, {v[0], 0}, {v[0], v[1]}, {0, v[1]}};
  }
  if (j.contains("objects")) {
    const json& o = j["objects"];
    if (!o.is_array()) {
      *error = "world: \"objects\" must be an array of [xmin, ymin, xmax, ymax]";
      return std::nullopt;
    }
    for (size_t i = 0; i < o.size(); ++i) {
      if (!ReadNumbers(o[i], 4, &v) || v[2] <= v[0] || v[3] <= v[1]) {
        *error = "world: \"objects\"[" + std::to_string(i) +
                 "] must be [xmin, ymin, xmax, ymax] with xmin < xmax and ymin < ymax";
        return std::nullopt;
      }
      w.objects.push_back({v[0], v[1], v[2], v[3]});
    }
  }
  if (!j.contains("start") || !ReadNumbers(j["start"], 3, &v)) {
    *error = "world: \"start\" must be [x, y, theta]";
    return std::nullopt;
  }
  w.start = {v[0], v[1], NormalizeAngle(v[2])};
  const Box b = w.Bounds();
  if (w.start.x <= b.xmin || w.start.x >= b.xmax || w.start.y <= b.ymin || w.start.y >= b.ymax) {
    *error = "world: \"start\" lies outside the room";
    return std::nullopt;
  }
  if (j.contains("seed")) {
    if (!j["seed"].is_number_integer()) {
      *error = "world: \"seed\" must be an integer";
      return std::nullopt;
    }
    w.seed = j["seed"].get<uint64_t>();
  }
  if (j.contains("noise")) {
    const json& n = j["noise"];
    if (!n.is_object()) {
      *error = "world: \"noise\" must be an object";
      return std::nullopt;
    }
    const std::pair<const char*, double*> keys[] = {
        {"wheel_radius_error_left", &w.noise.wheel_radius_error_left},
        {"wheel_radius_error_right", &w.noise.wheel_radius_error_right},
        {"slip_sigma", &w.noise.slip_sigma},
        {"ir_voltage_sigma_rel", &w.noise.ir_voltage_sigma_rel},
        {"ir_period_s", &w.noise.ir_period_s},
        {"ir_period_jitter_s", &w.noise.ir_period_jitter_s},
        {"ir_beam_deg", &w.noise.ir_beam_deg},
    };
    for (const auto& [k, p] : keys) {
      if (!n.contains(k)) continue;
      const bool signed_ok = std::string_view(k).rfind("wheel_radius_error", 0) == 0;
      if (!n[k].is_number() || n[k].get<double>() < (signed_ok ? -0.5 : 0.0)) {
        *error = std::string("world: \"noise.") + k + "\" must be a number >= " +
                 (signed_ok ? "-0.5" : "0");
        return std::nullopt;
      }
      *p = n[k].get<double>();
    }
    if (w.noise.ir_period_s < 0.005) {
      *error = "world: \"noise.ir_period_s\" must be >= 0.005";
      return std::nullopt;
    }
  }
  return w;
}

std::optional<World> LoadWorldFile(const std::string& path, std::string* error) {
  std::string text;
  if (!ReadRegularFile(path, kMaxWorldBytes, &text, error)) {
    *error = "world: " + *error;
    return std::nullopt;
  }
  auto w = ParseWorld(text, error);
  if (!w) *error = path + ": " + *error;
  return w;
}

std::optional<double> RayCast(const std::vector<Segment>& segs, Vec2 p, double angle,
                              double max_range) {
  const double dx = std::cos(angle), dy = std::sin(angle);
  std::optional<double> best;
  for (const Segment& s : segs) {
    const double ex = s.b.x - s.a.x, ey = s.b.y - s.a.y;
    const double den = dx * ey - dy * ex;
    if (std::abs(den) < 1e-12) continue;
    const double wx = s.a.x - p.x, wy = s.a.y - p.y;
    const double t = (wx * ey - wy * ex) / den;  // along the ray
    const double u = (wx * dy - wy * dx) / den;  // along the segment
    if (t < 0 || u < 0 || u > 1 || t > max_range) continue;
    if (!best || t < *best) best = t;
  }
  return best;
}

double PointSegmentDistance(Vec2 p, const Segment& s, Vec2* closest) {
  const double ex = s.b.x - s.a.x, ey = s.b.y - s.a.y;
  const double len2 = ex * ex + ey * ey;
  double u = len2 > 0 ? ((p.x - s.a.x) * ex + (p.y - s.a.y) * ey) / len2 : 0;
  u = std::clamp(u, 0.0, 1.0);
  const Vec2 c{s.a.x + u * ex, s.a.y + u * ey};
  if (closest) *closest = c;
  return std::hypot(p.x - c.x, p.y - c.y);
}

}  // namespace irslam::sim
