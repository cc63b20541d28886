#include "control/room_model.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>

#include "control/room_geometry.h"

namespace irslam::control {
namespace {

using room_geometry::CornerEnd;
using room_geometry::FaceBox;
using room_geometry::InsidePolygon;
using room_geometry::MakeCorner;
using room_geometry::Meets;
using room_geometry::Overlap1d;
using room_geometry::Side;
using room_geometry::ToSides;

int Find(std::vector<int>& parent, int i) {
  while (parent[static_cast<size_t>(i)] != i)
    i = parent[static_cast<size_t>(i)] =
        parent[static_cast<size_t>(parent[static_cast<size_t>(i)])];
  return i;
}

}  // namespace

options::Table<ModelOptions> ModelKeys() {
  using O = ModelOptions;
  static constexpr options::Key<O> kKeys[] = {
      {"axis_tolerance_rad", &O::axis_tolerance_rad, 0.001, 0.7, "rad",
       "lines this close to an axis count as axis-aligned"},
      {"collinear_m", &O::collinear_m, 0.001, 1, "m",
       "pieces of one wall or side: offsets within this"},
      {"corner_m", &O::corner_m, 0.01, 2, "m",
       "two sides meet: their corner within this of an end"},
      {"wall_contact_m", &O::wall_contact_m, 0.01, 2, "m",
       "an object this close to a wall touches it"},
      {"wall_reach_m", &O::wall_reach_m, 0, 2, "m",
       "a side ending this close to a wall (along it) runs into it"},
      {"same_size_m", &O::same_size_m, 0, 2, "m",
       "a piece of furniture that moved since the saved map is recognised by its size within this"},
      {"merge_touching_m", &O::merge_touching_m, 0, 1, "m",
       "incomplete objects whose boxes are this close are pieces of one (0: off)"},
      {"trace_band_m", &O::trace_band_m, 0.05, 3, "m",
       "a wall-contact object's contour along the wall (a free object's own contour, beside the edge) this close "
       "to the middle of an edge of its box, outside it, went past that side (its last side is inferred)"},
      {"narrow_gap_m", &O::narrow_gap_m, 0, 3, "m",
       "a free object's one unmapped side facing a wall closer than this is inferred once its contour has left "
       "it along that wall (the robot cannot go between; 0: off)"},
  };
  return kKeys;
}

const char* ToString(ObjectKind k) {
  return k == ObjectKind::kWallContact ? "wall_contact" : "free";
}

int EnvironmentModel::pending() const {
  int n = 0;
  for (const auto& o : objects) n += !o.complete && !o.given_up;
  return n;
}

namespace {
constexpr char kByContour[] = "one side inferred from the contour";
constexpr char kAlongWall[] = "one side inferred from the contour along the wall";
constexpr char kNearWall[] = "the side facing the wall inferred (too near it to go between)";
constexpr char kWentPast[] = "one side inferred from the contour that went past it";

// Which side inference a saved complete object's note names (nullptr: none).
const char* SavedInference(const std::string& note) {
  for (const char* why : {kAlongWall, kNearWall, kWentPast, kByContour}) {
    if (note.find(why) != std::string::npos) return why;
  }
  return nullptr;
}
}  // namespace

bool Modeler::CloseByContour(int object_id, const std::vector<Eigen::Vector2d>& loop,
                             const std::vector<slam::LineFeature>& lines,
                             const std::vector<TimedPose>& trajectory) {
  // Remembered either way: a third side found later still closes it.
  closed_by_contour_.push_back(object_id);
  if (loop.size() >= 3) contour_loops_.push_back(loop);
  return CompleteAfterUpdate(object_id, lines, trajectory);
}

bool Modeler::CloseAlongWall(int object_id, const std::vector<Eigen::Vector2d>& trace,
                             const std::vector<slam::LineFeature>& lines,
                             const std::vector<TimedPose>& trajectory) {
  if (!trace.empty()) {
    // The same contour left again (a free target's trace grows while it is
    // followed): its longer trace replaces the last.
    if (!wall_traces_.empty() && wall_traces_.back().first == object_id &&
        wall_traces_.back().second.front() == trace.front()) {
      wall_traces_.back().second = trace;
    } else {
      wall_traces_.emplace_back(object_id, trace);
    }
  }
  return CompleteAfterUpdate(object_id, lines, trajectory);
}

bool Modeler::CloseNearWall(int object_id, const std::vector<slam::LineFeature>& lines,
                            const std::vector<TimedPose>& trajectory) {
  if (std::find(left_near_wall_.begin(), left_near_wall_.end(), object_id) == left_near_wall_.end()) {
    left_near_wall_.push_back(object_id);
  }
  return CompleteAfterUpdate(object_id, lines, trajectory);
}

bool Modeler::CompleteAfterUpdate(int object_id, const std::vector<slam::LineFeature>& lines,
                                  const std::vector<TimedPose>& trajectory) {
  Update(lines, trajectory);
  for (const auto& o : model_.objects) {
    if (o.id == object_id) return o.complete;
  }
  return false;
}

void Modeler::NoteMoved(int id, const Box& was) {
  moved_.emplace_back(id, was);
  // Its contour and any giving up were where it stood: found again, it is
  // judged on what is seen of it there.
  closed_by_contour_.erase(std::remove(closed_by_contour_.begin(), closed_by_contour_.end(), id),
                           closed_by_contour_.end());
  inferred_.erase(std::remove_if(inferred_.begin(), inferred_.end(), [&](const auto& i) { return i.first == id; }),
                  inferred_.end());
  left_near_wall_.erase(std::remove(left_near_wall_.begin(), left_near_wall_.end(), id), left_near_wall_.end());
  wall_traces_.erase(
      std::remove_if(wall_traces_.begin(), wall_traces_.end(), [&](const auto& w) { return w.first == id; }),
      wall_traces_.end());
  given_up_.erase(std::remove_if(given_up_.begin(), given_up_.end(), [&](const auto& g) { return g.first == id; }),
                  given_up_.end());
  model_.objects.erase(std::remove_if(model_.objects.begin(), model_.objects.end(),
                                      [&](const ObjectModel& o) { return o.id == id; }),
                       model_.objects.end());
}

void Modeler::Seed(const EnvironmentModel& saved, std::vector<TimedPose> saved_trajectory) {
  model_ = saved;
  seeded_ = true;
  saved_ids_.clear();
  moved_.clear();
  new_ids_.clear();
  notes_.clear();
  for (const auto& o : saved.objects) saved_ids_.push_back(o.id);
  prior_trajectory_ = std::move(saved_trajectory);
  given_up_.clear();
  closed_by_contour_.clear();
  inferred_.clear();
  left_near_wall_.clear();
  contour_loops_.clear();
  wall_traces_.clear();
  next_id_ = 1;
  for (const auto& o : saved.objects) {
    next_id_ = std::max(next_id_, o.id + 1);
    // (Complete stays complete, with the inference its note names: a side
    // inferred from a contour, all round or along or near a wall, is not
    // inferred again without it.)
    if (o.complete) inferred_.emplace_back(o.id, SavedInference(o.note));
    if (o.given_up) given_up_.emplace_back(o.id, o.note);
  }
}

void Modeler::GiveUp(int object_id, const std::string& why) {
  given_up_.emplace_back(object_id, why);
  for (auto& o : model_.objects) {
    if (o.id == object_id) {
      o.given_up = true;
      o.note = why;
    }
  }
}

namespace {

// The Room: the outermost sides seen from inside. Bottom: horizontal, seen from
// above, lowest; top: seen from below, highest; left/right likewise in x. Marks
// the sides that are walls.
RoomModel FindRoom(const std::vector<Side>& sides, double collinear_m, std::vector<bool>* is_wall) {
  RoomModel room;
  is_wall->assign(sides.size(), false);
  const auto pick = [&](bool horizontal, int seen_from, int wall_index) -> std::optional<double> {
    std::optional<double> extreme;
    for (const auto& s : sides) {
      if (s.horizontal != horizontal || s.seen_from != seen_from) continue;
      if (!extreme || (seen_from > 0 ? s.c < *extreme : s.c > *extreme)) extreme = s.c;
    }
    if (!extreme) return std::nullopt;
    for (size_t i = 0; i < sides.size(); ++i) {
      const auto& s = sides[i];
      if (s.horizontal == horizontal && s.seen_from == seen_from &&
          std::abs(s.c - *extreme) < collinear_m) {
        (*is_wall)[i] = true;
        room.walls[static_cast<size_t>(wall_index)].push_back(s.id);
      }
    }
    return extreme;
  };
  const auto bottom = pick(true, +1, 0);
  const auto right = pick(false, -1, 1);
  const auto top = pick(true, -1, 2);
  const auto left = pick(false, +1, 3);
  if (bottom && right && top && left && *left < *right && *bottom < *top) {
    room.box = Box{*left, *bottom, *right, *top};
  }
  return room;
}

// The sides that are not walls, grouped into objects where they meet (or lie
// inside one contour loop); side_in_loop: per side, inside a contour loop.
std::vector<std::vector<size_t>> GroupObjects(
    const std::vector<Side>& sides, const std::vector<bool>& is_wall,
    const std::vector<std::vector<Eigen::Vector2d>>& contour_loops, const ModelOptions& o,
    std::vector<bool>* side_in_loop) {
  std::vector<size_t> rest;
  for (size_t i = 0; i < sides.size(); ++i) {
    if (!is_wall[i]) rest.push_back(i);
  }
  // Sides inside one contour loop the robot has gone all round are one object.
  std::vector<int> loop_of(rest.size(), -1);
  for (size_t i = 0; i < rest.size(); ++i) {
    const Side& sd = sides[rest[i]];
    const Eigen::Vector2d mid = 0.5 * (sd.End(0) + sd.End(1));
    for (size_t k = 0; k < contour_loops.size(); ++k) {
      if (InsidePolygon(contour_loops[k], mid)) loop_of[i] = static_cast<int>(k);
    }
  }
  std::vector<int> parent(rest.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (size_t i = 0; i < rest.size(); ++i) {
    for (size_t j = i + 1; j < rest.size(); ++j) {
      if ((loop_of[i] >= 0 && loop_of[i] == loop_of[j]) ||
          Meets(sides[rest[i]], sides[rest[j]], o)) {
        parent[static_cast<size_t>(Find(parent, static_cast<int>(i)))] =
            Find(parent, static_cast<int>(j));
      }
    }
  }
  std::vector<std::vector<size_t>> groups;
  std::vector<int> group_of(rest.size(), -1);
  for (size_t i = 0; i < rest.size(); ++i) {
    const int root = Find(parent, static_cast<int>(i));
    if (group_of[static_cast<size_t>(root)] < 0) {
      group_of[static_cast<size_t>(root)] = static_cast<int>(groups.size());
      groups.emplace_back();
    }
    groups[static_cast<size_t>(group_of[static_cast<size_t>(root)])].push_back(rest[i]);
  }
  side_in_loop->assign(sides.size(), false);
  for (size_t i = 0; i < rest.size(); ++i) (*side_in_loop)[rest[i]] = loop_of[i] >= 0;
  return groups;
}

// Open ends: a line end that meets neither another side of the object
// (orthogonal, at a corner; or collinear) nor a wall of the room. touches_wall:
// set if an end was closed by a wall.
int OpenEnds(const std::vector<Side>& sides, const std::vector<size_t>& g, const RoomModel& room,
             const ModelOptions& o, bool* touches_wall) {
  const auto near_wall = [&](const Eigen::Vector2d& p) {
    if (!room.box) return false;
    const Box& r = *room.box;
    return std::abs(p.x() - r.xmin) < o.wall_contact_m ||
           std::abs(p.x() - r.xmax) < o.wall_contact_m ||
           std::abs(p.y() - r.ymin) < o.wall_contact_m ||
           std::abs(p.y() - r.ymax) < o.wall_contact_m;
  };
  int open = 0;
  for (size_t i : g) {
    const Side& s = sides[i];
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector2d e = s.End(k);
      bool closed = false;
      for (size_t j : g) {
        if (j == i) continue;
        const Side& t = sides[j];
        if (t.horizontal != s.horizontal) {
          // The corner rule, for this end of s (the corner's position along t
          // is s's offset).
          const Eigen::Vector2d corner =
              s.horizontal ? Eigen::Vector2d(t.c, s.c) : Eigen::Vector2d(s.c, t.c);
          const CornerEnd this_end{(corner - e).norm(), false};
          const CornerEnd along_t{std::min((t.End(0) - corner).norm(), (t.End(1) - corner).norm()),
                                  s.c > t.a0 && s.c < t.a1};
          if (MakeCorner(this_end, along_t, o.corner_m)) closed = true;
        } else if (std::abs(t.c - s.c) < o.collinear_m &&
                   std::min((t.End(0) - e).norm(), (t.End(1) - e).norm()) < o.corner_m) {
          closed = true;
        }
      }
      if (!closed && near_wall(e)) {
        closed = true;
        *touches_wall = true;
      }
      if (!closed && room.box) {
        // A side running into a wall: the inner corner it makes with the wall
        // is seen from the follow distance at best, so its end is seen short
        // of the wall - by up to wall_reach_m.
        const Box& r = *room.box;
        const double along = s.horizontal ? e.x() : e.y();
        const double lo = s.horizontal ? r.xmin : r.ymin, hi = s.horizontal ? r.xmax : r.ymax;
        const bool toward_lo = k == 0, toward_hi = k == 1;  // a0 <= a1: end 0 is the lower one
        if ((toward_lo && along - lo < o.wall_reach_m) ||
            (toward_hi && hi - along < o.wall_reach_m)) {
          closed = true;
          *touches_wall = true;
        }
      }
      open += closed ? 0 : 1;
    }
  }
  return open;
}

// One object from its group of sides: lines, box, open ends, kind, complete.
ObjectModel BuildObject(const std::vector<Side>& sides, const std::vector<size_t>& g,
                        const RoomModel& room, const ModelOptions& o) {
  ObjectModel obj;
  Box b{1e18, 1e18, -1e18, -1e18};
  for (size_t i : g) {
    const Side& s = sides[i];
    obj.lines.push_back(s.id);
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector2d e = s.End(k);
      b.xmin = std::min(b.xmin, e.x());
      b.xmax = std::max(b.xmax, e.x());
      b.ymin = std::min(b.ymin, e.y());
      b.ymax = std::max(b.ymax, e.y());
    }
  }
  bool touches_wall = false;
  obj.open_ends = OpenEnds(sides, g, room, o, &touches_wall);
  // The walls the box lies against: their sides are never seen (one wall: 3
  // sides to map; in a corner of the room, two walls: 2).
  const size_t walls_touched =
      room.box ? static_cast<size_t>(std::abs(b.xmin - room.box->xmin) < o.wall_contact_m) +
                     static_cast<size_t>(std::abs(b.xmax - room.box->xmax) < o.wall_contact_m) +
                     static_cast<size_t>(std::abs(b.ymin - room.box->ymin) < o.wall_contact_m) +
                     static_cast<size_t>(std::abs(b.ymax - room.box->ymax) < o.wall_contact_m)
               : 0;
  obj.kind = (touches_wall || walls_touched > 0) ? ObjectKind::kWallContact : ObjectKind::kFree;
  const size_t needed = obj.kind == ObjectKind::kWallContact
                            ? std::max<size_t>(2, 4 - std::min<size_t>(walls_touched, 2))
                            : 4;
  obj.complete = obj.open_ends == 0 && obj.lines.size() >= needed;
  obj.box = FaceBox(sides, g, b);
  std::sort(obj.lines.begin(), obj.lines.end());
  return obj;
}

// A box's edges, numbered 0 bottom, 1 right, 2 top, 3 left: its offset (y for
// the horizontal edges 0 and 2, x for the others) and the way out of the box
// across it (-1: toward the lesser coordinate, as Side::seen_from).
double EdgeOffset(const Box& b, int e) {
  return e == 0 ? b.ymin : e == 1 ? b.xmax : e == 2 ? b.ymax : b.xmin;
}
int EdgeOutward(int e) { return e == 0 || e == 3 ? -1 : 1; }

// The one edge of an object's box that is neither against a wall nor a face
// seen from outside; -1 if there is none or more than one.
int MissingEdge(const std::vector<Side>& sides, const std::vector<size_t>& g, const Box& b,
                const RoomModel& room, const ModelOptions& o) {
  if (!room.box || b.width() < 2 * o.collinear_m || b.height() < 2 * o.collinear_m) return -1;
  int missing = -1;
  for (int e = 0; e < 4; ++e) {
    const double at = EdgeOffset(b, e);
    if (std::abs(at - EdgeOffset(*room.box, e)) < o.wall_contact_m) continue;
    const bool horizontal = e % 2 == 0;
    const bool face = std::any_of(g.begin(), g.end(), [&](size_t i) {
      const Side& s = sides[i];
      return s.horizontal == horizontal && s.seen_from == EdgeOutward(e) && std::abs(s.c - at) < o.collinear_m;
    });
    if (face) continue;
    if (missing >= 0) return -1;
    missing = e;
  }
  return missing;
}

// A trace went past edge e of box b outside it: a point beyond the edge within
// band_m of its middle. (Not over the edge itself: beside a short side that
// meets a wall the robot keeps its follow distance from the wall too, and
// passes its corner rather than its middle.)
// With `within_span`, the point is also beside the edge (a free object's: a
// trace down a neighbouring side past its end would pass a short edge's middle
// within the band).
bool TracePassesEdge(const std::vector<Eigen::Vector2d>& trace, const Box& b, int e, double band_m,
                     bool within_span) {
  const bool horizontal = e % 2 == 0;
  const double at = EdgeOffset(b, e);
  const double outward = EdgeOutward(e);
  const Eigen::Vector2d mid = horizontal ? Eigen::Vector2d(0.5 * (b.xmin + b.xmax), at)
                                         : Eigen::Vector2d(at, 0.5 * (b.ymin + b.ymax));
  return std::any_of(trace.begin(), trace.end(), [&](const Eigen::Vector2d& p) {
    const double off = outward * ((horizontal ? p.y() : p.x()) - at);
    const double along = horizontal ? p.x() : p.y();
    const bool beside = horizontal ? along >= b.xmin && along <= b.xmax : along >= b.ymin && along <= b.ymax;
    return off > 0 && (p - mid).norm() < band_m && (beside || !within_span);
  });
}

// Incomplete objects whose boxes touch (within merge_touching_m) are pieces of
// one: compound furniture whose step between its boxes was too short to map.
// Groups with a side inside a followed contour are left as the contour joined them.
// `groups` in, the joined groups out; `objects`: one built object per group out.
void MergeTouching(const std::vector<Side>& sides, const std::vector<bool>& side_in_loop, const RoomModel& room,
                   const ModelOptions& o, std::vector<std::vector<size_t>>* groups,
                   std::vector<ObjectModel>* objects) {
  std::vector<std::vector<size_t>>& gs = *groups;
  std::vector<ObjectModel>& objs = *objects;
  objs.clear();
  for (const auto& g : gs) objs.push_back(BuildObject(sides, g, room, o));
  if (o.merge_touching_m <= 0) return;
  const auto mergeable = [&](size_t k) {
    return !objs[k].complete && std::none_of(gs[k].begin(), gs[k].end(), [&](size_t i) { return side_in_loop[i]; });
  };
  // After each join the scan starts again: the joined box may now touch another.
  for (bool merged = true; merged;) {
    merged = false;
    for (size_t i = 0; i < gs.size() && !merged; ++i) {
      if (!mergeable(i)) continue;
      for (size_t j = i + 1; j < gs.size() && !merged; ++j) {
        if (!mergeable(j)) continue;
        const Box& a = objs[i].box;
        const Box& b = objs[j].box;
        if (Overlap1d(a.xmin, a.xmax, b.xmin, b.xmax) > -o.merge_touching_m &&
            Overlap1d(a.ymin, a.ymax, b.ymin, b.ymax) > -o.merge_touching_m) {
          gs[i].insert(gs[i].end(), gs[j].begin(), gs[j].end());
          gs.erase(gs.begin() + static_cast<std::ptrdiff_t>(j));
          objs.erase(objs.begin() + static_cast<std::ptrdiff_t>(j));
          objs[i] = BuildObject(sides, gs[i], room, o);
          merged = true;
        }
      }
    }
  }
}

}  // namespace

void Modeler::NameNewObject(ObjectModel* obj) {
  // Not in the saved map: a piece that moved (about the same size), or a new one.
  if (TakeMoved(obj)) return;
  notes_.emplace_back(obj->id, "new since the saved map");
  new_ids_.push_back(obj->id);
}

bool Modeler::TakeMoved(ObjectModel* obj) {
  // Centre of box a from box b's.
  const auto shift = [](const Box& a, const Box& b) {
    return Eigen::Vector2d(0.5 * (a.xmin + a.xmax - b.xmin - b.xmax), 0.5 * (a.ymin + a.ymax - b.ymin - b.ymax));
  };
  const auto same = std::find_if(moved_.begin(), moved_.end(), [&](const auto& mv) {
    const Box& b = mv.second;
    const bool upright = std::abs(b.width() - obj->box.width()) <= options_.same_size_m &&
                         std::abs(b.height() - obj->box.height()) <= options_.same_size_m;
    const bool turned = std::abs(b.width() - obj->box.height()) <= options_.same_size_m &&
                        std::abs(b.height() - obj->box.width()) <= options_.same_size_m;
    // Where it was (its lines not out of the map yet): not the piece found again.
    return (upright || turned) && shift(obj->box, b).norm() > options_.same_size_m;
  });
  if (same == moved_.end()) return false;
  obj->id = same->first;
  const Box& b = same->second;
  const auto cm = [](double v) { return std::to_string(static_cast<int>(std::lround(100 * v))); };
  notes_.emplace_back(obj->id, "moved since the saved map by " + cm(shift(obj->box, b).norm()) + " cm (was at [" +
                                   cm(b.xmin) + ", " + cm(b.ymin) + ", " + cm(b.xmax) + ", " + cm(b.ymax) +
                                   "] cm)");
  moved_.erase(same);
  return true;
}

void Modeler::RenameNewAsMoved(ObjectModel* obj) {
  // Modelled (as new) before the saved piece was found missing: once it is
  // complete, and so has its true size, it may be that piece. So may one
  // given up with three sides or more (a contour that timed out in a tight
  // gap): its box spans its sides, and TakeMoved asks for the piece's size.
  const auto fresh = std::find(new_ids_.begin(), new_ids_.end(), obj->id);
  const bool sized = obj->complete || (obj->given_up && obj->lines.size() >= 3);
  if (!sized || moved_.empty() || fresh == new_ids_.end()) return;
  const int was = obj->id;
  if (!TakeMoved(obj)) return;
  new_ids_.erase(fresh);
  notes_.erase(std::remove_if(notes_.begin(), notes_.end(), [&](const auto& n) { return n.first == was; }),
               notes_.end());
  std::replace(closed_by_contour_.begin(), closed_by_contour_.end(), was, obj->id);
  for (auto& i : inferred_) {
    if (i.first == was) i.first = obj->id;
  }
  std::replace(left_near_wall_.begin(), left_near_wall_.end(), was, obj->id);
  for (auto& w : wall_traces_) {
    if (w.first == was) w.first = obj->id;
  }
  for (auto& g : given_up_) {
    if (g.first == was) g.first = obj->id;
  }
  obj->note = notes_.back().second;
}

void Modeler::AssignIds(EnvironmentModel* m, const std::vector<bool>& group_in_loop,
                        const std::vector<std::vector<int>>& passed_by,
                        const std::vector<bool>& group_narrow) {
  // Stable ids: an object keeps the id of the previous object it overlaps most.
  std::vector<bool> taken(model_.objects.size(), false);
  for (size_t gi = 0; gi < m->objects.size(); ++gi) {
    ObjectModel& obj = m->objects[gi];
    double best = 0;
    int best_k = -1;
    for (size_t k = 0; k < model_.objects.size(); ++k) {
      if (taken[k]) continue;
      const Box& p = model_.objects[k].box;
      const double ix = Overlap1d(obj.box.xmin, obj.box.xmax, p.xmin, p.xmax) + 0.1;
      const double iy = Overlap1d(obj.box.ymin, obj.box.ymax, p.ymin, p.ymax) + 0.1;
      if (ix <= 0 || iy <= 0) continue;
      if (ix * iy > best) {
        best = ix * iy;
        best_k = static_cast<int>(k);
      }
    }
    if (best_k >= 0) {
      taken[static_cast<size_t>(best_k)] = true;
      obj.id = model_.objects[static_cast<size_t>(best_k)].id;
    } else {
      obj.id = next_id_++;
      if (seeded_) NameNewObject(&obj);
    }
    for (const auto& [nid, note] : notes_) {
      if (nid == obj.id && obj.note.empty()) obj.note = note;
    }
    // Gone all round (now or in an earlier call): one side is inferred.
    const bool contoured =
        group_in_loop[gi] || std::find(closed_by_contour_.begin(), closed_by_contour_.end(),
                                       obj.id) != closed_by_contour_.end();
    if (contoured && !obj.complete && obj.lines.size() >= 3) {
      obj.complete = true;
      // (After a note saying where it came from: "moved ..." stays first.)
      obj.note = obj.note.empty() ? kByContour : obj.note + "; " + kByContour;
    }
    // Inferred along or near a wall, now or earlier (or complete in a saved map):
    // a wall-contact object's side by any contour along the wall that went
    // past it, a free object's only by its own.
    const std::vector<int>& by = passed_by[gi];
    const bool passed = obj.kind == ObjectKind::kFree
                            ? std::find(by.begin(), by.end(), obj.id) != by.end()
                            : !by.empty();
    const auto known = std::find_if(inferred_.begin(), inferred_.end(),
                                    [&](const auto& i) { return i.first == obj.id; });
    const bool near_wall =
        group_narrow[gi] &&
        std::find(left_near_wall_.begin(), left_near_wall_.end(), obj.id) != left_near_wall_.end();
    if ((known != inferred_.end() || passed || near_wall) && !obj.complete &&
        obj.lines.size() >= 2) {
      obj.complete = true;
      const char* why = known != inferred_.end() ? known->second
                        : !passed                            ? kNearWall
                        : obj.kind == ObjectKind::kFree      ? kWentPast
                                                             : kAlongWall;
      if (known == inferred_.end()) inferred_.emplace_back(obj.id, why);
      if (why != nullptr) obj.note = obj.note.empty() ? why : obj.note + "; " + why;
    }
    for (const auto& [gid, why] : given_up_) {
      if (gid == obj.id && !obj.complete) {
        // (A contoured object that has since been closed is not given up.)
        obj.given_up = true;
        obj.note = obj.note.empty() ? why : obj.note + "; " + why;  // ("moved ..." stays first)
      }
    }
    if (seeded_) RenameNewAsMoved(&obj);
  }
}

const EnvironmentModel& Modeler::Update(const std::vector<slam::LineFeature>& lines,
                                        const std::vector<TimedPose>& trajectory) {
  std::vector<TimedPose> with_prior;
  if (!prior_trajectory_.empty()) {
    with_prior = prior_trajectory_;
    with_prior.insert(with_prior.end(), trajectory.begin(), trajectory.end());
  }
  const std::vector<Side> sides =
      ToSides(lines, prior_trajectory_.empty() ? trajectory : with_prior, options_.axis_tolerance_rad);
  EnvironmentModel m;
  std::vector<bool> is_wall;
  m.room = FindRoom(sides, options_.collinear_m, &is_wall);
  std::vector<bool> side_in_loop;
  auto groups = GroupObjects(sides, is_wall, contour_loops_, options_, &side_in_loop);
  MergeTouching(sides, side_in_loop, m.room, options_, &groups, &m.objects);
  std::vector<bool> group_in_loop, group_narrow;
  std::vector<std::vector<int>> passed_by;
  for (size_t gi = 0; gi < groups.size(); ++gi) {
    const auto& g = groups[gi];
    group_in_loop.push_back(
        std::any_of(g.begin(), g.end(), [&](size_t i) { return side_in_loop[i]; }));
    const ObjectModel& obj = m.objects[gi];
    // The one edge neither against a wall nor a face seen from outside, if
    // that is all that is missing.
    const int e = !obj.complete && obj.lines.size() >= (obj.kind == ObjectKind::kFree ? 3U : 2U)
                      ? MissingEdge(sides, g, obj.box, m.room, options_)
                      : -1;
    // It is where the robot went past (a wall-contact object's free sides
    // followed along the wall, or a free object's three sides followed on):
    // which targets' traces did.
    std::vector<int> by;
    for (const auto& [id, tr] : wall_traces_) {
      if (e >= 0 && TracePassesEdge(tr, obj.box, e, options_.trace_band_m, obj.kind == ObjectKind::kFree)) {
        by.push_back(id);
      }
    }
    passed_by.push_back(std::move(by));
    // A free object's one side not mapped faces a wall too near for the robot to go between.
    const double to_wall =
        e >= 0 ? std::abs(EdgeOffset(obj.box, e) - EdgeOffset(*m.room.box, e)) : 0;
    group_narrow.push_back(e >= 0 && obj.kind == ObjectKind::kFree && options_.narrow_gap_m > 0 &&
                           to_wall < options_.narrow_gap_m);
  }
  AssignIds(&m, group_in_loop, passed_by, group_narrow);
  std::sort(m.objects.begin(), m.objects.end(),
            [](const auto& a, const auto& b) { return a.id < b.id; });
  model_ = std::move(m);
  return model_;
}

}  // namespace irslam::control
