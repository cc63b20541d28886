#include "sim/world.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "io/file_io.h"
#include "io/json_text.h"
#include "io/option_json.h"

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

// Whether p is inside the room's outline (ray crossing; points on an edge count).
bool InsideOutline(const std::vector<Vec2>& poly, Vec2 p) {
  bool inside = false;
  for (size_t i = 0, k = poly.size() - 1; i < poly.size(); k = i++) {
    const Vec2 a = poly[i], b = poly[k];
    if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) inside = !inside;
  }
  return inside;
}

// A box lies in the room when its centre and its corners (pulled 1 mm inwards,
// so a box against a wall counts) are inside the outline.
bool InsideRoom(const World& w, const Box& o) {
  constexpr double kIn = 1e-3;
  const Vec2 pts[] = {{(o.xmin + o.xmax) / 2, (o.ymin + o.ymax) / 2},
                      {o.xmin + kIn, o.ymin + kIn}, {o.xmax - kIn, o.ymin + kIn},
                      {o.xmax - kIn, o.ymax - kIn}, {o.xmin + kIn, o.ymax - kIn}};
  for (const Vec2& p : pts) {
    if (!InsideOutline(w.outline, p)) return false;
  }
  return true;
}

// ParseWorld's parts, in the order it checks them; each false after setting
// *error.
bool CheckKnownKeys(const json& j, std::string* error) {
  for (const auto& [key, value] : j.items()) {
    static constexpr std::string_view kKnown[] = {"name",  "room", "outline", "objects",
                                                  "start", "seed", "noise"};
    if (std::find(std::begin(kKnown), std::end(kKnown), key) == std::end(kKnown)) {
      *error = "world: \"" + OneLine(key) + "\" is not a known key";
      return false;
    }
  }
  return true;
}

// "outline" (an axis-aligned polygon) or else "room" (a rectangle).
bool ReadOutline(const json& j, World* w, std::string* error) {
  std::vector<double> v;
  if (!j.contains("outline")) {
    if (!j.contains("room") || !ReadNumbers(j["room"], 2, &v) || v[0] <= 0.5 || v[1] <= 0.5) {
      *error = "world: \"room\" must be [width, height] in metres (each > 0.5)";
      return false;
    }
    w->outline = {{0, 0}, {v[0], 0}, {v[0], v[1]}, {0, v[1]}};
    return true;
  }
  const json& o = j["outline"];
  if (!o.is_array() || o.size() < 4) {
    *error = "world: \"outline\" must be a closed polygon of at least 4 [x, y] points";
    return false;
  }
  for (size_t i = 0; i < o.size(); ++i) {
    if (!ReadNumbers(o[i], 2, &v)) {
      *error = "world: \"outline\"[" + std::to_string(i) + "] must be [x, y]";
      return false;
    }
    w->outline.push_back({v[0], v[1]});
  }
  for (size_t i = 0; i < w->outline.size(); ++i) {
    const Vec2 a = w->outline[i], b = w->outline[(i + 1) % w->outline.size()];
    if (a.x != b.x && a.y != b.y) {
      *error = "world: \"outline\" edge " + std::to_string(i) + " is not axis-aligned";
      return false;
    }
  }
  return true;
}

bool ReadObjects(const json& j, World* w, std::string* error) {
  if (!j.contains("objects")) return true;
  const json& o = j["objects"];
  if (!o.is_array()) {
    *error = "world: \"objects\" must be an array of [xmin, ymin, xmax, ymax]";
    return false;
  }
  std::vector<double> v;
  for (size_t i = 0; i < o.size(); ++i) {
    if (!ReadNumbers(o[i], 4, &v) || v[2] <= v[0] || v[3] <= v[1]) {
      *error = "world: \"objects\"[" + std::to_string(i) +
               "] must be [xmin, ymin, xmax, ymax] with xmin < xmax and ymin < ymax";
      return false;
    }
    w->objects.push_back({v[0], v[1], v[2], v[3]});
  }
  return true;
}

// "start", inside the room and outside every object, each object inside the room.
bool ReadStart(const json& j, World* w, std::string* error) {
  std::vector<double> v;
  if (!j.contains("start") || !ReadNumbers(j["start"], 3, &v)) {
    *error = "world: \"start\" must be [x, y, theta]";
    return false;
  }
  w->start = {v[0], v[1], NormalizeAngle(v[2])};
  const Box b = w->Bounds();
  if (w->start.x <= b.xmin || w->start.x >= b.xmax || w->start.y <= b.ymin ||
      w->start.y >= b.ymax) {
    *error = "world: \"start\" lies outside the room";
    return false;
  }
  for (size_t i = 0; i < w->objects.size(); ++i) {
    const Box& o = w->objects[i];
    const std::string which = "world: \"objects\"[" + std::to_string(i) + "]";
    if (!InsideRoom(*w, o)) {
      *error = which + " lies outside the room";
      return false;
    }
    if (w->start.x > o.xmin && w->start.x < o.xmax && w->start.y > o.ymin && w->start.y < o.ymax) {
      *error = "world: \"start\" lies inside " + which.substr(7);
      return false;
    }
  }
  return true;
}

// The optional "seed" and "noise".
bool ReadSeedAndNoise(const json& j, World* w, std::string* error) {
  if (j.contains("seed")) {
    if (!j["seed"].is_number_integer()) {
      *error = "world: \"seed\" must be an integer";
      return false;
    }
    w->seed = j["seed"].get<uint64_t>();
  }
  if (j.contains("noise")) {
    if (!options::ReadObject(j["noise"], "noise", options::Bind(&w->noise, SimNoiseKeys()),
                             error)) {
      *error = "world: " + *error;
      return false;
    }
  }
  return true;
}

}  // namespace

options::Table<SimNoise> SimNoiseKeys() {
  using N = SimNoise;
  static constexpr options::Key<N> kKeys[] = {
      {"wheel_radius_error_left", &N::wheel_radius_error_left, -0.5, 0.5, "",
       "relative error of the left wheel's true radius"},
      {"wheel_radius_error_right", &N::wheel_radius_error_right, -0.5, 0.5, "",
       "relative error of the right wheel's true radius"},
      {"slip_sigma", &N::slip_sigma, 0, 1, "", "wheel slip, relative, per physics step, per wheel"},
      {"ir_voltage_sigma_rel", &N::ir_voltage_sigma_rel, 0, 1, "", "IR output noise, relative to the voltage"},
      {"ir_period_s", &N::ir_period_s, 0.005, 1, "s", "IR measurement period"},
      {"ir_period_jitter_s", &N::ir_period_jitter_s, 0, 1, "s", "IR measurement period jitter"},
      {"ir_beam_deg", &N::ir_beam_deg, 0, 90, "deg", "IR beam width"},
      {"wheel_base_error", &N::wheel_base_error, -0.5, 0.5, "", "relative error of the true track width"},
      {"slip_correlation_s", &N::slip_correlation_s, 0, 60, "s",
       "> 0: slip correlated over this time and growing in turns (carpet); 0: white per step"},
      {"ir_surface_bias_m", &N::ir_surface_bias_m, 0, 0.5, "m",
       "each wall and object face gets a fixed range bias drawn from +- this"},
      {"ir_max_incidence_deg", &N::ir_max_incidence_deg, 10, 90, "deg",
       "returns beyond this incidence angle drop out; noise grows as 1/cos(incidence)"},
      {"ir_outlier_rate", &N::ir_outlier_rate, 0, 1, "", "fraction of readings that are a uniform random range"},
  };
  return kKeys;
}

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
  if (!CheckKnownKeys(j, error)) return std::nullopt;
  World w;
  if (j.contains("name")) {
    if (!j.at("name").is_string()) {
      *error = "world: \"name\" must be a string";
      return std::nullopt;
    }
    w.name = j["name"].get<std::string>();
  }
  if (!ReadOutline(j, &w, error) || !ReadObjects(j, &w, error) || !ReadStart(j, &w, error) ||
      !ReadSeedAndNoise(j, &w, error))
    return std::nullopt;
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
                              double max_range, size_t* hit) {
  const double dx = std::cos(angle), dy = std::sin(angle);
  std::optional<double> best;
  for (size_t i = 0; i < segs.size(); ++i) {
    const Segment& s = segs[i];
    const double ex = s.b.x - s.a.x, ey = s.b.y - s.a.y;
    const double den = dx * ey - dy * ex;
    if (std::abs(den) < 1e-12) continue;
    const double wx = s.a.x - p.x, wy = s.a.y - p.y;
    const double t = (wx * ey - wy * ex) / den;  // along the ray
    const double u = (wx * dy - wy * dx) / den;  // along the segment
    if (t < 0 || u < 0 || u > 1 || t > max_range) continue;
    if (!best || t < *best) {
      best = t;
      if (hit != nullptr) *hit = i;
    }
  }
  return best;
}

Vec2 ClosestOnSegment(Vec2 p, const Segment& s) {
  const double ex = s.b.x - s.a.x, ey = s.b.y - s.a.y;
  const double len2 = ex * ex + ey * ey;
  double u = len2 > 0 ? ((p.x - s.a.x) * ex + (p.y - s.a.y) * ey) / len2 : 0;
  u = std::clamp(u, 0.0, 1.0);
  return {s.a.x + u * ex, s.a.y + u * ey};
}

double PointSegmentDistance(Vec2 p, const Segment& s, Vec2* closest) {
  const Vec2 c = ClosestOnSegment(p, s);
  if (closest) *closest = c;
  return std::hypot(p.x - c.x, p.y - c.y);
}

}  // namespace irslam::sim
