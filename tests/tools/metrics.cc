#include "tests/tools/metrics.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <type_traits>
#include <variant>

namespace irslam::metrics {
namespace {

const TimedPose& Nearest(const std::vector<TimedPose>& v, double t) {
  auto it =
      std::lower_bound(v.begin(), v.end(), t, [](const TimedPose& p, double x) { return p.t < x; });
  if (it == v.end()) return v.back();
  if (it != v.begin() && std::abs(std::prev(it)->t - t) < std::abs(it->t - t))
    return *std::prev(it);
  return *it;
}

}  // namespace

std::vector<TimedPose> ToWorld(const std::vector<TimedPose>& internal,
                               const Pose2& start) {
  std::vector<TimedPose> out;
  out.reserve(internal.size());
  for (const auto& p : internal) out.push_back({p.t, Compose(start, p.pose)});
  return out;
}

double PositionErrorAt(const std::vector<TimedPose>& est, const std::vector<TimedPose>& truth,
                       double t) {
  const Pose2& a = Nearest(est, t).pose;
  const Pose2& b = Nearest(truth, t).pose;
  return std::hypot(a.x - b.x, a.y - b.y);
}

PoseErrors ComparePoses(const std::vector<TimedPose>& est, const std::vector<TimedPose>& truth) {
  PoseErrors e;
  if (est.empty() || truth.empty()) return e;
  double sp = 0, sh = 0;
  for (const auto& p : est) {
    const Pose2& q = Nearest(truth, p.t).pose;
    const double dp = std::hypot(p.pose.x - q.x, p.pose.y - q.y);
    const double dh = NormalizeAngle(p.pose.theta - q.theta);
    sp += dp * dp;
    sh += dh * dh;
    e.max_position_m = std::max(e.max_position_m, dp);
  }
  e.rms_position_m = std::sqrt(sp / static_cast<double>(est.size()));
  e.rms_heading_rad = std::sqrt(sh / static_cast<double>(est.size()));
  const Pose2& a = est.back().pose;
  const Pose2& b = Nearest(truth, est.back().t).pose;
  e.final_position_m = std::hypot(a.x - b.x, a.y - b.y);
  e.final_heading_rad = std::abs(NormalizeAngle(a.theta - b.theta));
  return e;
}

std::vector<LineError> CompareLines(const std::vector<slam::LineFeature>& lines, const Pose2& start,
                                    const sim::World& world, int* unmatched) {
  std::vector<std::pair<sim::Segment, bool>> truth;
  for (size_t i = 0; i < world.outline.size(); ++i) {
    truth.push_back({{world.outline[i], world.outline[(i + 1) % world.outline.size()]}, true});
  }
  for (const auto& b : world.objects) {
    const sim::Vec2 c[4] = {{b.xmin, b.ymin}, {b.xmax, b.ymin}, {b.xmax, b.ymax}, {b.xmin, b.ymax}};
    for (int k = 0; k < 4; ++k) truth.push_back({{c[k], c[(k + 1) % 4]}, false});
  }
  std::vector<LineError> out;
  int missing = 0;
  for (const auto& l : lines) {
    const Pose2 a = Compose(start, {l.p0.x(), l.p0.y(), 0});
    const Pose2 b = Compose(start, {l.p1.x(), l.p1.y(), 0});
    const double ang = std::atan2(b.y - a.y, b.x - a.x);
    const double mx = 0.5 * (a.x + b.x), my = 0.5 * (a.y + b.y);
    double best = 1e9;
    LineError be;
    for (const auto& [s, wall] : truth) {
      const double ta = std::atan2(s.b.y - s.a.y, s.b.x - s.a.x);
      double da = std::remainder(ang - ta, M_PI);
      const double len = std::hypot(s.b.x - s.a.x, s.b.y - s.a.y);
      const double ux = (s.b.x - s.a.x) / len, uy = (s.b.y - s.a.y) / len;
      // Distances of the end points from the true (infinite) line.
      const double d0 = std::abs((a.x - s.a.x) * uy - (a.y - s.a.y) * ux);
      const double d1 = std::abs((b.x - s.a.x) * uy - (b.y - s.a.y) * ux);
      const double along = (mx - s.a.x) * ux + (my - s.a.y) * uy;
      if (std::abs(da) > 6 * M_PI / 180 || 0.5 * (d0 + d1) > 0.15) continue;
      if (along < -0.3 || along > len + 0.3) continue;
      const double score = 0.5 * (d0 + d1) + 0.2 * std::abs(da);
      if (score < best) {
        best = score;
        const bool vertical = std::abs(ux) < 0.5;
        // Signed offset of the mapped midpoint along +x (vertical) or +y (horizontal).
        const double off = vertical ? mx - s.a.x : my - s.a.y;
        be = {l.id, da, off, vertical, wall, 0.5 * (d0 + d1), std::abs(da), l.length()};
      }
    }
    if (best < 1e9) {
      out.push_back(be);
    } else {
      ++missing;
    }
  }
  if (unmatched) *unmatched = missing;
  return out;
}

Pose2 BestAlignment(const std::vector<slam::LineFeature>& lines, const Pose2& start,
                    const sim::World& world) {
  // Rotation: the length-weighted mean angle error; then translation: the mean
  // offsets of vertical lines (x) and horizontal lines (y), after that rotation.
  int unmatched;
  std::vector<LineError> e = CompareLines(lines, start, world, &unmatched);
  double sw = 0, sa = 0;
  for (const auto& l : e) {
    sw += l.length_m;
    sa += l.length_m * l.signed_angle_rad;
  }
  if (sw <= 0) return {};
  const double rot = -sa / sw;
  e = CompareLines(lines, CorrectStart(start, {0, 0, rot}), world, &unmatched);
  double wx = 0, sx = 0, wy = 0, sy = 0;
  for (const auto& l : e) {
    if (l.vertical) {
      wx += l.length_m;
      sx += l.length_m * l.signed_offset_m;
    } else {
      wy += l.length_m;
      sy += l.length_m * l.signed_offset_m;
    }
  }
  return {wx > 0 ? -sx / wx : 0.0, wy > 0 ? -sy / wy : 0.0, rot};
}

Pose2 RoomFrameStart(const std::vector<slam::LineFeature>& lines, const sim::World& world) {
  return CorrectStart(world.start, BestAlignment(lines, world.start, world));
}

Pose2 CorrectStart(const Pose2& start, const Pose2& c) {
  // Rotate about the start position, then shift.
  return {start.x + c.x, start.y + c.y, NormalizeAngle(start.theta + c.theta)};
}

ObjectScores ScoreObjects(const nlohmann::json& map, const slam::Slam& slam,
                          const sim::World& world, double impassable_gap_m) {
  // True pieces: union of touching boxes, and of boxes closer than the IR beam's
  // footprint at 1 m (5 deg: 9 cm), which no sensor can resolve nor the robot pass:
  // a bed and the night table 2-10 cm beside it (sim/generator.cc CornerPiece) are
  // one piece of furniture to the robot.
  constexpr double kJoinGapM = 0.10;
  std::vector<sim::Box> pieces;
  std::vector<bool> used(world.objects.size(), false);
  for (size_t i = 0; i < world.objects.size(); ++i) {
    if (used[i]) continue;
    sim::Box b = world.objects[i];
    used[i] = true;
    for (bool grew = true; grew;) {
      grew = false;
      for (size_t k = 0; k < world.objects.size(); ++k) {
        const auto& c = world.objects[k];
        if (used[k] || c.xmin > b.xmax + kJoinGapM || c.xmax < b.xmin - kJoinGapM ||
            c.ymin > b.ymax + kJoinGapM || c.ymax < b.ymin - kJoinGapM) {
          continue;
        }
        b = {std::min(b.xmin, c.xmin), std::min(b.ymin, c.ymin), std::max(b.xmax, c.xmax),
             std::max(b.ymax, c.ymax)};
        used[k] = grew = true;
      }
    }
    pieces.push_back(b);
  }
  const sim::Box room = world.Bounds();
  const Pose2 fixed = RoomFrameStart(slam.lines(), world);
  const double rot = slam.map_rotation();
  int found = 0, kind_ok = 0, complete = 0, extra = 0;
  int good = 0, good_complete = 0;
  double max_edge = 0, iou_sum = 0;
  std::vector<bool> matched(pieces.size(), false);
  for (const auto& o : map["objects"]) {
    // Map-frame box -> world box.
    double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
    for (int cx = 0; cx < 2; ++cx) {
      for (int cy = 0; cy < 2; ++cy) {
        const double mx = o["box"][cx ? 2 : 0], my = o["box"][cy ? 3 : 1];
        const double ix = std::cos(-rot) * mx - std::sin(-rot) * my,
                     iy = std::sin(-rot) * mx + std::cos(-rot) * my;
        const Pose2 w = Compose(fixed, {ix, iy, 0});
        x0 = std::min(x0, w.x), x1 = std::max(x1, w.x), y0 = std::min(y0, w.y),
        y1 = std::max(y1, w.y);
      }
    }
    int best = -1;
    double best_iou = 0;
    for (size_t k = 0; k < pieces.size(); ++k) {
      const auto& p = pieces[k];
      const double ix = std::min(x1, p.xmax) - std::max(x0, p.xmin),
                   iy = std::min(y1, p.ymax) - std::max(y0, p.ymin);
      const double inter = std::max(0.0, ix) * std::max(0.0, iy);
      const double uni = (x1 - x0) * (y1 - y0) + (p.xmax - p.xmin) * (p.ymax - p.ymin) - inter;
      const double iou = uni > 0 ? inter / uni : 0;
      // A line-only object has no area: count it by proximity.
      const bool near = ix > -0.05 && iy > -0.05;
      if ((iou > best_iou || (best < 0 && near)) && !matched[k]) {
        best_iou = iou;
        best = static_cast<int>(k);
      }
    }
    if (best < 0) {
      ++extra;
      continue;
    }
    matched[static_cast<size_t>(best)] = true;
    const auto& p = pieces[static_cast<size_t>(best)];
    ++found;
    // Per side: the gap to the wall it faces, and whether that side is hidden
    // from the robot (touching, or closer than the robot can pass).
    const double gap[4] = {p.xmin - room.xmin, p.ymin - room.ymin, room.xmax - p.xmax, room.ymax - p.ymax};
    bool wall = false, hidden[4];
    for (int k = 0; k < 4; ++k) {
      wall = wall || gap[k] < 0.05;
      hidden[k] = gap[k] < std::max(0.05, impassable_gap_m);
    }
    const bool near_wall = hidden[0] || hidden[1] || hidden[2] || hidden[3];
    const bool kind_right = (o["kind"] == "wall_contact") == wall || (near_wall && !wall);
    kind_ok += kind_right;
    complete += o["complete"].get<bool>();
    if (kind_right && best_iou >= 0.5) {
      ++good;
      good_complete += o["complete"].get<bool>();
    }
    // Edges: a wall-contact piece's wall side is never seen; skip it.
    const double e[4] = {hidden[0] ? 0 : std::abs(x0 - p.xmin), hidden[1] ? 0 : std::abs(y0 - p.ymin),
                         hidden[2] ? 0 : std::abs(x1 - p.xmax), hidden[3] ? 0 : std::abs(y1 - p.ymax)};
    if (o["complete"].get<bool>()) max_edge = std::max({max_edge, e[0], e[1], e[2], e[3]});
    iou_sum += best_iou;
  }
  ObjectScores sc;
  sc.pieces = static_cast<int>(pieces.size());
  sc.found = found;
  sc.kind_right = kind_ok;
  sc.complete = complete;
  sc.extra = extra;
  sc.good = good;
  sc.good_complete = good_complete;
  sc.max_edge_m = max_edge;
  sc.mean_iou = found ? iou_sum / found : 0;
  return sc;
}

bool IsClutter(const sim::Box& b) {
  return b.xmax - b.xmin <= kClutterM + 1e-9 && b.ymax - b.ymin <= kClutterM + 1e-9;
}

bool ContactWithClutter(const sim::World& world, double x, double y) {
  const sim::Vec2 p{x, y};
  double nearest = 1e18;
  for (size_t k = 0; k < world.outline.size(); ++k) {
    const sim::Segment side{world.outline[k], world.outline[(k + 1) % world.outline.size()]};
    sim::Vec2 closest;
    nearest = std::min(nearest, sim::PointSegmentDistance(p, side, &closest));
  }
  bool clutter = false;
  for (const sim::Box& b : world.objects) {
    const double dx = std::max({b.xmin - x, 0.0, x - b.xmax}), dy = std::max({b.ymin - y, 0.0, y - b.ymax});
    const double d = std::hypot(dx, dy);
    if (d < nearest) {
      nearest = d;
      clutter = IsClutter(b);
    }
  }
  return clutter;
}

bool SetNoiseNominal(const std::string& csv, sim::SimNoise* noise, std::string* error) {
  const sim::SimNoise nominal;
  std::stringstream list(csv);
  for (std::string name; std::getline(list, name, ',');) {
    if (name.empty()) continue;
    bool found = false;
    for (const auto& key : sim::SimNoiseKeys()) {
      if (key.name != name) continue;
      found = true;
      std::visit([&](auto member) {
        if constexpr (std::is_same_v<decltype(member), double sim::SimNoise::*>) noise->*member = nominal.*member;
      }, key.member);
    }
    if (!found) {
      *error = "unknown noise key '" + name + "' (the world file's noise keys, contracts §1)";
      return false;
    }
  }
  return true;
}

}  // namespace irslam::metrics
