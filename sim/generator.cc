#include "sim/generator.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "io/option_json.h"

namespace irslam::sim {
namespace {

constexpr double kRobotRadiusM = 0.17;  // types/robot.h's default body radius

class Draw {
 public:
  explicit Draw(std::mt19937_64* rng) : rng_(rng) {}
  double Uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(*rng_); }
  int Int(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(*rng_); }
  bool Chance(double p) { return Uniform(0, 1) < p; }
  // A signed magnitude: uniform in [-m, m].
  double Signed(double m) { return Uniform(-m, m); }
  // Rounded to 5 mm, as a person would measure furniture.
  double Length(double lo, double hi) { return std::round(Uniform(lo, hi) / 0.005) * 0.005; }

 private:
  std::mt19937_64* rng_;
};

bool Overlaps(const Box& a, const Box& b, double gap) {
  return a.xmin < b.xmax + gap && b.xmin < a.xmax + gap && a.ymin < b.ymax + gap && b.ymin < a.ymax + gap;
}

// Places a piece (one or more boxes, relative to its own origin) at a free place:
// every box within the room and at least `gap` from every box already there.
class Layout {
 public:
  Layout(double width, double height) : w_(width), h_(height) {}

  bool Fits(const std::vector<Box>& piece, double gap) const {
    for (const Box& b : piece) {
      if (b.xmin < -1e-9 || b.ymin < -1e-9 || b.xmax > w_ + 1e-9 || b.ymax > h_ + 1e-9) return false;
      for (const Box& o : boxes_) {
        if (Overlaps(b, o, gap)) return false;
      }
    }
    return true;
  }
  void Add(const std::vector<Box>& piece) { boxes_.insert(boxes_.end(), piece.begin(), piece.end()); }
  const std::vector<Box>& boxes() const { return boxes_; }

  // Tries random placements of a piece built by make(x, y); keeps the first that fits.
  template <class Make>
  bool Place(Make make, double gap) {
    for (int attempt = 0; attempt < 200; ++attempt) {
      std::vector<Box> piece = make();
      if (Fits(piece, gap)) {
        Add(piece);
        return true;
      }
    }
    return false;
  }

  double w() const { return w_; }
  double h() const { return h_; }

 private:
  double w_, h_;
  std::vector<Box> boxes_;
};

Box At(double x, double y, double sx, double sy) { return {x, y, x + sx, y + sy}; }

// A box against one wall (sometimes a little off it: closer than the robot passes).
std::vector<Box> WallPiece(Layout& l, Draw& d) {
  const double along = d.Length(0.4, 1.8), depth = d.Length(0.3, 0.8);
  const double off = d.Chance(0.2) ? d.Length(0.05, 0.25) : 0.0;
  switch (d.Int(0, 3)) {
    case 0: return {At(d.Uniform(0, l.w() - along), off, along, depth)};                  // bottom
    case 1: return {At(l.w() - depth - off, d.Uniform(0, l.h() - along), depth, along)};  // right
    case 2: return {At(d.Uniform(0, l.w() - along), l.h() - depth - off, along, depth)};  // top
    default: return {At(off, d.Uniform(0, l.h() - along), depth, along)};                 // left
  }
}

// A box in a room corner (a bed), sometimes with a night table beside it.
std::vector<Box> CornerPiece(Layout& l, Draw& d) {
  const double sx = d.Length(0.8, 2.0), sy = d.Length(0.6, 1.6);
  const int corner = d.Int(0, 3);
  const double x = (corner == 1 || corner == 2) ? l.w() - sx : 0.0;
  const double y = corner >= 2 ? l.h() - sy : 0.0;
  std::vector<Box> piece = {At(x, y, sx, sy)};
  if (d.Chance(0.5)) {
    const double n = d.Length(0.35, 0.5), gap = d.Chance(0.5) ? 0.0 : d.Length(0.02, 0.1);
    const double ny = y == 0 ? 0.0 : l.h() - n;
    piece.push_back(x == 0 ? At(sx + gap, ny, n, n) : At(x - gap - n, ny, n, n));
  }
  return piece;
}

// A free box, or a compound of 2-3 touching boxes, or an L shape.
std::vector<Box> FreePiece(Layout& l, Draw& d, int kind) {
  const double sx = d.Length(0.3, 1.2), sy = d.Length(0.3, 1.2);
  const double x = d.Uniform(0.2, std::max(0.21, l.w() - sx - 0.2));
  const double y = d.Uniform(0.2, std::max(0.21, l.h() - sy - 0.2));
  std::vector<Box> piece = {At(x, y, sx, sy)};
  if (kind == 0) return piece;
  const int extra = kind == 1 ? d.Int(1, 2) : 1;
  for (int i = 0; i < extra; ++i) {
    const Box& b = piece.back();
    const double ex = d.Length(0.3, 0.8), ey = d.Length(0.3, 0.8);
    if (kind == 2) {  // L: the second box on top of the first's left end
      piece.push_back(At(b.xmin, b.ymax, std::min(ex, b.xmax - b.xmin), ey));
    } else if (d.Chance(0.5)) {  // touching on the right, shifted
      piece.push_back(At(b.xmax, b.ymin + d.Uniform(-0.2, 0.2), ex, ey));
    } else {  // touching on top, shifted
      piece.push_back(At(b.xmin + d.Uniform(-0.2, 0.2), b.ymax, ex, ey));
    }
  }
  return piece;
}

// Clutter: four legs (2-6 cm) at the corners of a table or a chair.
std::vector<Box> Legs(Layout& l, Draw& d) {
  const double s = d.Length(0.02, 0.06), sx = d.Length(0.4, 1.4), sy = d.Length(0.4, 1.0);
  const double x = d.Uniform(0.3, std::max(0.31, l.w() - sx - 0.3));
  const double y = d.Uniform(0.3, std::max(0.31, l.h() - sy - 0.3));
  return {At(x, y, s, s), At(x + sx - s, y, s, s), At(x, y + sy - s, s, s), At(x + sx - s, y + sy - s, s, s)};
}

}  // namespace

std::optional<NoiseProfile> ParseNoiseProfile(std::string_view name) {
  if (name == "nominal") return NoiseProfile::kNominal;
  if (name == "realistic") return NoiseProfile::kRealistic;
  if (name == "harsh") return NoiseProfile::kHarsh;
  return std::nullopt;
}

const char* ToString(NoiseProfile p) {
  switch (p) {
    case NoiseProfile::kNominal: return "nominal";
    case NoiseProfile::kRealistic: return "realistic";
    case NoiseProfile::kHarsh: return "harsh";
  }
  return "?";
}

SimNoise DrawNoise(NoiseProfile profile, std::mt19937_64* rng) {
  SimNoise n;  // nominal: the simulator's defaults
  if (profile == NoiseProfile::kNominal) return n;
  const bool harsh = profile == NoiseProfile::kHarsh;
  Draw d(rng);
  n.wheel_radius_error_left = d.Signed(harsh ? 0.02 : 0.01);
  n.wheel_radius_error_right = d.Signed(harsh ? 0.02 : 0.01);
  n.wheel_base_error = d.Signed(harsh ? 0.04 : 0.02);
  n.slip_sigma = d.Uniform(0.005, harsh ? 0.04 : 0.02);
  n.slip_correlation_s = d.Uniform(0.5, 3.0);
  n.ir_voltage_sigma_rel = d.Uniform(0.015, harsh ? 0.035 : 0.025);
  n.ir_surface_bias_m = d.Uniform(0.0, harsh ? 0.04 : 0.02);
  n.ir_max_incidence_deg = d.Uniform(harsh ? 60.0 : 70.0, 90.0);
  n.ir_outlier_rate = d.Uniform(0.0, harsh ? 0.02 : 0.005);
  return n;
}

World GenerateWorld(uint64_t seed, NoiseProfile profile) {
  std::mt19937_64 rng(seed * 0x2545F4914F6CDD1DULL + 17);
  Draw d(&rng);
  const double width = d.Length(3.0, 8.0), height = d.Length(3.0, 7.0);
  Layout layout(width, height);
  const int pieces = d.Int(0, 6);
  std::vector<Box> free_pieces;
  for (int i = 0; i < pieces; ++i) {
    const int kind = d.Int(0, 5);
    // Gaps between pieces from 0.2 m (impassable) to 1.5 m.
    const double gap = d.Uniform(0.2, 1.5);
    switch (kind) {
      case 0: layout.Place([&] { return WallPiece(layout, d); }, gap); break;
      case 1: layout.Place([&] { return CornerPiece(layout, d); }, gap); break;
      case 5: layout.Place([&] { return Legs(layout, d); }, gap); break;
      default: {
        const size_t before = layout.boxes().size();
        if (layout.Place([&] { return FreePiece(layout, d, kind - 2); }, gap)) {
          free_pieces.push_back(layout.boxes()[before]);
        }
      }
    }
  }
  World w;
  w.name = "gen-" + std::string(ToString(profile)) + "-" + std::to_string(seed);
  w.outline = {{0, 0}, {width, 0}, {width, height}, {0, height}};
  w.objects = layout.boxes();
  w.seed = seed;
  w.noise = DrawNoise(profile, &rng);
  // The start: anywhere free (0.1 m between the body and everything), any heading;
  // sometimes beside a free object, sometimes facing a corner of the room.
  const double need = kRobotRadiusM + 0.1;
  const bool beside = !free_pieces.empty() && d.Chance(0.25);
  for (int attempt = 0; attempt < 5000; ++attempt) {
    double x = d.Uniform(need, width - need), y = d.Uniform(need, height - need);
    if (beside && attempt < 2500) {
      const Box& b = free_pieces[static_cast<size_t>(d.Int(0, static_cast<int>(free_pieces.size()) - 1))];
      x = d.Uniform(b.xmin - 0.5, b.xmax + 0.5);
      y = d.Uniform(b.ymin - 0.5, b.ymax + 0.5);
    }
    if (x < need || y < need || x > width - need || y > height - need) continue;
    if (ClearanceAt(w, x, y) < need) continue;
    double theta = d.Uniform(-M_PI, M_PI);
    if (d.Chance(0.15)) {  // facing the nearest corner
      const double cx = x < width / 2 ? 0 : width, cy = y < height / 2 ? 0 : height;
      theta = std::atan2(cy - y, cx - x);
    }
    w.start = {x, y, NormalizeAngle(theta)};
    return w;
  }
  // A room so full there is no free place (not seen in practice): drop the furniture.
  w.objects.clear();
  w.start = {width / 2, height / 2, 0};
  return w;
}

double ClearanceAt(const World& w, double x, double y) {
  double best = 1e9;
  for (const Segment& s : w.Segments()) best = std::min(best, PointSegmentDistance({x, y}, s, nullptr));
  for (const Box& b : w.objects) {
    if (x > b.xmin && x < b.xmax && y > b.ymin && y < b.ymax) return 0;
  }
  return best;
}

nlohmann::json WorldToJson(const World& w) {
  const Box b = w.Bounds();
  nlohmann::json objects = nlohmann::json::array();
  for (const Box& o : w.objects) objects.push_back({o.xmin, o.ymin, o.xmax, o.ymax});
  SimNoise noise = w.noise;
  nlohmann::json n = nlohmann::json::object();
  for (const auto& e : options::Bind(&noise, SimNoiseKeys())) n[std::string(e.name)] = options::EntryValue(e);
  nlohmann::json j = {{"name", w.name},
                      {"room", {b.xmax - b.xmin, b.ymax - b.ymin}},
                      {"objects", objects},
                      {"start", {w.start.x, w.start.y, w.start.theta}},
                      {"noise", n}};
  if (w.seed) j["seed"] = *w.seed;
  return j;
}

}  // namespace irslam::sim
