#include "tests/tools/reloc_eval.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <set>
#include <sstream>

#include "sim/sim_run.h"

namespace irslam::metrics {
namespace {

constexpr double kDeg = 180.0 / M_PI;

std::string F(double v, int prec = 1) {
  char b[32];
  std::snprintf(b, sizeof b, "%.*f", prec, v);
  return b;
}

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const double at = q * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<size_t>(std::floor(at));
  const size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (v[hi] - v[lo]) * (at - static_cast<double>(lo));
}

bool Wrong(const PoseError& e, const RelocOptions& ro) {
  return e.position_m > ro.wrong_position_m || e.heading_rad > ro.wrong_heading_rad;
}

PoseError Max(const PoseError& a, const PoseError& b) {
  return {std::max(a.position_m, b.position_m), std::max(a.heading_rad, b.heading_rad)};
}

// The centre of a box (the world's sim::Box or the model's control::Box).
template <typename B>
Eigen::Vector2d Centre(const B& b) {
  return {0.5 * (b.xmin + b.xmax), 0.5 * (b.ymin + b.ymax)};
}

// The centre of a map-frame box in the world frame.
Eigen::Vector2d CentreInWorld(const control::Box& b, const Pose2& map_to_world) {
  const Eigen::Vector2d m = Centre(b);
  const Pose2 c = Compose(map_to_world, Pose2{m.x(), m.y(), 0});
  return {c.x, c.y};
}

// Distance between two axis-aligned boxes (0 when they touch or overlap).
double Gap(const sim::Box& a, const sim::Box& b) {
  const double gx = std::max({0.0, b.xmin - a.xmax, a.xmin - b.xmax});
  const double gy = std::max({0.0, b.ymin - a.ymax, a.ymin - b.ymax});
  return std::hypot(gx, gy);
}

// The bounding box of the world's boxes `boxes` (one piece of furniture).
sim::Box Bounds(const sim::World& world, const std::vector<size_t>& boxes) {
  sim::Box b{1e18, 1e18, -1e18, -1e18};
  for (size_t k : boxes) {
    const sim::Box& o = world.objects[k];
    b = {std::min(b.xmin, o.xmin), std::min(b.ymin, o.ymin), std::max(b.xmax, o.xmax), std::max(b.ymax, o.ymax)};
  }
  return b;
}

// The saved map's object for the piece made of the world's `boxes`: the one
// whose centre lies nearest the piece's, within 0.3 m; 0 if none.
int SavedObjectFor(const sim::World& world, const std::vector<size_t>& boxes, const robot::MapSnapshot& saved,
                   const Pose2& map_to_world) {
  const Eigen::Vector2d c = Centre(Bounds(world, boxes));
  int id = 0;
  double best = 0.3;
  for (const auto& o : saved.objects) {
    const double d = (CentreInWorld(o.box, map_to_world) - c).norm();
    if (d < best) {
      best = d;
      id = o.id;
    }
  }
  return id;
}

// The move for run `seed`: a piece the saved map modelled, one of the four
// directions, among the allowed ones (uniform); world_index -1 if none. A
// piece is all the boxes that touch (FurniturePieces): an L-shaped desk is
// two boxes in a world file and moves as one.
RelocRun::Moved PickMove(const sim::World& world, const robot::MapSnapshot& saved, const Pose2& map_to_world,
                         const RelocOptions& ro, uint64_t seed) {
  std::vector<RelocRun::Moved> candidates;
  const double steps[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  for (const std::vector<size_t>& piece : FurniturePieces(world)) {
    const int id = SavedObjectFor(world, piece, saved, map_to_world);
    if (id == 0) continue;
    for (const auto& s : steps) {
      if (!MovePiece(world, piece, s[0] * ro.move_m, s[1] * ro.move_m, ro.move_gap_m)) continue;
      RelocRun::Moved m;
      m.world_index = static_cast<int>(piece.front());
      m.boxes = piece;
      m.saved_id = id;
      m.dx = s[0] * ro.move_m;
      m.dy = s[1] * ro.move_m;
      candidates.push_back(m);
    }
  }
  if (candidates.empty()) return {};
  std::mt19937_64 rng(seed * 104729 + 7);
  return candidates[std::uniform_int_distribution<size_t>(0, candidates.size() - 1)(rng)];
}

// Scores the move against the run's final map: the piece's saved id at its new
// place with a note, nothing left where it was.
void ScoreMove(const sim::World& before, const robot::MapSnapshot& out, const Pose2& map_to_world,
               const RelocOptions& ro, RelocRun::Moved* m) {
  const Eigen::Vector2d old_c = Centre(Bounds(before, m->boxes)), new_c = old_c + Eigen::Vector2d(m->dx, m->dy);
  bool at_new = false, left_at_old = false;
  m->box = "gone";
  for (const auto& o : out.objects) {
    const Eigen::Vector2d c = CentreInWorld(o.box, map_to_world);
    if ((c - old_c).norm() <= ro.moved_match_m) left_at_old = true;
    if (o.id != m->saved_id) continue;
    m->noted = o.note.rfind("moved", 0) == 0;
    at_new = (c - new_c).norm() <= ro.moved_match_m;
    m->box = F(c.x(), 2) + ", " + F(c.y(), 2);
  }
  m->updated = at_new && !left_at_old;
}

// Saved objects other than `moved_id` that end noted "moved ..." or gone from `out`.
int OthersDisturbed(const robot::MapSnapshot& saved, const robot::MapSnapshot& out, int moved_id) {
  int n = 0;
  for (const auto& s : saved.objects) {
    if (s.id == moved_id) continue;
    const auto o = std::find_if(out.objects.begin(), out.objects.end(), [&](const auto& x) { return x.id == s.id; });
    n += o == out.objects.end() || o->note.rfind("moved", 0) == 0;
  }
  return n;
}

// One run from `start` in `base`; unmoved: the world before a piece was moved
// (RelocOptions::move_m; `moved` says which), to score the move.
RelocRun RunOne(const sim::World& base, const robot::CoreOptions& options,
                const robot::MapSnapshot& saved, const Pose2& map_to_world, const Pose2& start,
                uint64_t seed, const RelocOptions& ro, const sim::World* unmoved = nullptr,
                const RelocRun::Moved& moved = {}) {
  RelocRun r;
  r.moved = moved;
  r.start = start;
  r.seed = seed;
  sim::World world = base;
  world.start = start;
  sim::RunSetup setup;
  setup.saved_map = saved;
  double wrong_since = -1;
  bool first_after_commit = true;
  const auto on_tick = [&](const sim::InProcessRun& run) {
    // Every period: a commit can be followed by done within a period or two
    // (nothing left to model), and the run ends there.
    const robot::CoreStatus st = run.core->Status(run.t);
    if (!st.relocalize) return;
    const bool committed = st.relocalize->committed;
    if (committed && !r.committed) {
      r.committed = true;
      r.commit_t = st.relocalize->committed_t > 0 ? st.relocalize->committed_t : run.t;
      r.relocalize_s = r.commit_t - st.relocalize->started_t;
      r.hypotheses = st.relocalize->hypotheses;
    }
    r.attempts = st.relocalize->attempts;
    if (!r.committed) return;
    const PoseError e = ErrorInWorld(st.slam.pose, map_to_world, run.sim->true_pose());
    if (first_after_commit) {
      r.at_commit = e;
      first_after_commit = false;
    }
    if (run.t >= r.commit_t + 5) {
      r.max_after = Max(r.max_after, e);
      r.after_sampled = true;
    }
    r.final_error = e;
    // Confidently wrong: committed and off for recover_s in a row (a return to
    // relocalising, or the error shrinking, ends the episode).
    if (committed && Wrong(e, ro)) {
      if (wrong_since < 0) wrong_since = run.t;
      if (run.t - wrong_since >= ro.recover_s) r.confidently_wrong = true;
    } else {
      wrong_since = -1;
    }
  };
  if (ro.move_m <= 0) {
    setup.stop_when = [&](const sim::InProcessRun& run) {
      return r.committed && run.t >= r.commit_t + ro.after_commit_s;
    };
  }
  robot::CoreOptions o = options;
  if (saved.calibration) o.slam.initial_calibration = saved.calibration;
  const sim::InProcessRun run =
      sim::RunInProcess(world, o, seed, ro.max_time_s, on_tick, nullptr, nullptr, setup);
  r.end_state =
      run.error.empty() ? control::ToString(run.core->state()) : "not started: " + run.error;
  r.end_t = run.t;
  const robot::MapSnapshot out = run.core->Map();
  if (!r.committed && out.relocalized) {
    // Committed after the last period's status (cannot be scored for error).
    r.committed = true;
    r.commit_t = out.relocalized->t;
    r.hypotheses = out.relocalized->hypotheses;
  }
  r.saved_lines = static_cast<int>(saved.lines.size());
  r.kept_ids = KeptLineIds(saved.lines, out.lines);
  r.duplicates = DuplicateLines(saved.lines, out.lines);
  // Still off when the run ended (done, or the time limit): never recovered.
  if (wrong_since >= 0) r.confidently_wrong = true;
  r.correct = r.committed && !r.confidently_wrong && !Wrong(r.final_error, ro);
  if (unmoved && moved.world_index >= 0) {
    ScoreMove(*unmoved, out, map_to_world, ro, &r.moved);
    // A run that never committed explored afresh: every saved object is
    // "gone" (new ids), which is no false report.
    if (r.committed) r.moved.others_disturbed = OthersDisturbed(saved, out, moved.saved_id);
  }
  return r;
}

}  // namespace

std::vector<TimedPose> Poses(const nlohmann::json& arr) {
  std::vector<TimedPose> out;
  for (const auto& p : arr) out.push_back({p[0], {p[1], p[2], p[3]}});
  return out;
}

Pose2 FitRigid(const std::vector<Eigen::Vector2d>& from, const std::vector<Eigen::Vector2d>& to,
               double* rms_m) {
  const size_t n = std::min(from.size(), to.size());
  if (rms_m) *rms_m = 0;
  if (n < 2) return {};
  Eigen::Vector2d ca = Eigen::Vector2d::Zero(), cb = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < n; ++i) {
    ca += from[i];
    cb += to[i];
  }
  ca /= static_cast<double>(n);
  cb /= static_cast<double>(n);
  double sxx = 0, sxy = 0, syx = 0, syy = 0;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d a = from[i] - ca, b = to[i] - cb;
    sxx += a.x() * b.x();
    sxy += a.x() * b.y();
    syx += a.y() * b.x();
    syy += a.y() * b.y();
  }
  const double theta = std::atan2(sxy - syx, sxx + syy);
  const Eigen::Matrix2d rot = Eigen::Rotation2Dd(theta).toRotationMatrix();
  const Eigen::Vector2d t = cb - rot * ca;
  if (rms_m) {
    double sum = 0;
    for (size_t i = 0; i < n; ++i) sum += (rot * from[i] + t - to[i]).squaredNorm();
    *rms_m = std::sqrt(sum / static_cast<double>(n));
  }
  return {t.x(), t.y(), NormalizeAngle(theta)};
}

Pose2 MapToWorldFit(const std::vector<TimedPose>& map_traj, const std::vector<TimedPose>& truth,
                    double* rms_m, double max_dt_s) {
  std::vector<Eigen::Vector2d> from, to;
  size_t j = 0;
  for (const TimedPose& m : map_traj) {
    while (j + 1 < truth.size() && std::abs(truth[j + 1].t - m.t) <= std::abs(truth[j].t - m.t))
      ++j;
    if (truth.empty() || std::abs(truth[j].t - m.t) > max_dt_s) continue;
    from.emplace_back(m.pose.x, m.pose.y);
    to.emplace_back(truth[j].pose.x, truth[j].pose.y);
  }
  return FitRigid(from, to, rms_m);
}

PoseError ErrorInWorld(const Pose2& map_pose, const Pose2& map_to_world, const Pose2& truth) {
  const Pose2 w = Compose(map_to_world, map_pose);
  return {std::hypot(w.x - truth.x, w.y - truth.y),
          std::abs(NormalizeAngle(w.theta - truth.theta))};
}

bool HasLineId(const std::vector<slam::LineFeature>& lines, int id) {
  return std::any_of(lines.begin(), lines.end(), [&](const slam::LineFeature& l) {
    return l.id == id || std::find(l.merged.begin(), l.merged.end(), id) != l.merged.end();
  });
}

int KeptLineIds(const std::vector<slam::LineFeature>& saved,
                const std::vector<slam::LineFeature>& out) {
  int kept = 0;
  for (const auto& l : saved) kept += HasLineId(out, l.id);
  return kept;
}

int DuplicateLines(const std::vector<slam::LineFeature>& saved,
                   const std::vector<slam::LineFeature>& out, double dist_m, double angle_rad) {
  std::set<int> saved_ids;
  for (const auto& l : saved) saved_ids.insert(l.id);
  int duplicates = 0;
  for (const auto& n : out) {
    if (saved_ids.count(n.id) || n.length() <= 0) continue;
    const Eigen::Vector2d nd = (n.p1 - n.p0).normalized();
    for (const auto& s : saved) {
      const double len = s.length();
      if (len <= 0) continue;
      const Eigen::Vector2d d = (s.p1 - s.p0) / len;
      const double angle = std::acos(std::min(1.0, std::abs(d.dot(nd))));  // undirected
      if (angle > angle_rad) continue;
      const Eigen::Vector2d normal(-d.y(), d.x());
      if (std::abs(normal.dot(n.p0 - s.p0)) > dist_m || std::abs(normal.dot(n.p1 - s.p0)) > dist_m)
        continue;
      const double a = d.dot(n.p0 - s.p0), b = d.dot(n.p1 - s.p0);
      if (std::max(a, b) <= 0 || std::min(a, b) >= len) continue;  // beyond its ends
      ++duplicates;
      break;
    }
  }
  return duplicates;
}

std::vector<Pose2> RandomFreeStarts(const sim::World& world, int n, double clearance_m,
                                    uint64_t seed) {
  std::mt19937_64 rng(seed);
  const sim::Box b = world.Bounds();
  std::uniform_real_distribution<double> ux(b.xmin, b.xmax), uy(b.ymin, b.ymax), uth(-M_PI, M_PI);
  std::vector<Pose2> out;
  std::string why;
  for (int tries = 0; static_cast<int>(out.size()) < n && tries < 1000 * n; ++tries) {
    const double x = ux(rng), y = uy(rng), th = uth(rng);
    const Pose2 p{x, y, th};
    if (sim::FreePose(world, p, clearance_m, &why)) out.push_back(p);
  }
  return out;
}

RelocWorld EvaluateRelocalization(const sim::World& world, const robot::CoreOptions& options,
                                  const RelocOptions& ro) {
  RelocWorld w;
  w.world = world.name;
  // The map: one exploration mission from the world's start.
  robot::CoreOptions explore = options;
  explore.mission.mode = "explore";
  const sim::InProcessRun first = sim::RunInProcess(world, explore, ro.seed, ro.map_max_time_s);
  w.map_done = first.core->state() == control::MissionState::kDone;
  w.map_t = first.t;
  const robot::MapSnapshot saved = first.core->Map();
  w.map_lines = static_cast<int>(saved.lines.size());
  w.map_objects = static_cast<int>(saved.objects.size());
  w.map_to_world =
      MapToWorldFit(saved.trajectory, Poses(first.sim->Truth()["trajectory"]), &w.fit_rms_m);
  const double clearance = options.slam.geometry.radius_m + ro.clearance_extra_m;
  const std::vector<Pose2> starts =
      RandomFreeStarts(world, ro.runs, clearance, ro.seed * 7919 + 13);
  if (ro.move_m <= 0) {
    for (size_t i = 0; i < starts.size(); ++i) {
      w.runs.push_back(RunOne(world, explore, saved, w.map_to_world, starts[i], ro.seed + 1 + i, ro));
    }
    return w;
  }
  // One piece moved per run, then the saved map's cleaning (the robot passes the piece).
  robot::CoreOptions clean = options;
  clean.mission.mode = "clean";
  for (int i = 0; i < ro.runs; ++i) {
    const uint64_t seed = ro.seed + 1 + static_cast<uint64_t>(i);
    const RelocRun::Moved m = PickMove(world, saved, w.map_to_world, ro, seed);
    const sim::World moved =
        m.world_index < 0 ? world : *MovePiece(world, m.boxes, m.dx, m.dy, ro.move_gap_m);
    const std::vector<Pose2> start = RandomFreeStarts(moved, 1, clearance, seed * 7919 + 13);
    if (start.empty()) continue;
    w.runs.push_back(RunOne(moved, clean, saved, w.map_to_world, start[0], seed, ro, &world, m));
  }
  return w;
}

std::vector<std::vector<size_t>> FurniturePieces(const sim::World& world) {
  constexpr double kTouch = 0.01;
  const size_t n = world.objects.size();
  std::vector<int> piece(n, -1);
  std::vector<std::vector<size_t>> out;
  for (size_t k = 0; k < n; ++k) {
    if (piece[k] >= 0) continue;
    piece[k] = static_cast<int>(out.size());
    out.push_back({k});
    for (size_t i = 0; i < out.back().size(); ++i) {  // breadth first over touching boxes
      const size_t a = out.back()[i];
      for (size_t b = 0; b < n; ++b) {
        if (piece[b] < 0 && Gap(world.objects[a], world.objects[b]) < kTouch) {
          piece[b] = piece[k];
          out.back().push_back(b);
        }
      }
    }
    std::sort(out.back().begin(), out.back().end());
  }
  return out;
}

std::optional<sim::World> MoveObject(const sim::World& world, size_t index, double dx, double dy,
                                     double gap_m) {
  return MovePiece(world, {index}, dx, dy, gap_m);
}

std::optional<sim::World> MovePiece(const sim::World& world, const std::vector<size_t>& boxes, double dx,
                                    double dy, double gap_m) {
  if (boxes.empty()) return std::nullopt;
  for (size_t k : boxes) {
    if (k >= world.objects.size()) return std::nullopt;
  }
  const auto in_piece = [&](size_t k) { return std::find(boxes.begin(), boxes.end(), k) != boxes.end(); };
  sim::World out = world;
  sim::World room = world;
  room.objects.clear();
  const std::vector<sim::Segment> walls = room.Segments();
  for (size_t index : boxes) {
    const sim::Box& was = world.objects[index];
    sim::Box& b = out.objects[index];
    b = {was.xmin + dx, was.ymin + dy, was.xmax + dx, was.ymax + dy};
    for (size_t k = 0; k < world.objects.size(); ++k) {
      if (!in_piece(k) && Gap(b, world.objects[k]) < gap_m) return std::nullopt;
    }
    // Inside the room: its corners (just inside) in the outline, no wall through it.
    constexpr double kIn = 1e-3;
    const Pose2 corners[] = {{b.xmin + kIn, b.ymin + kIn, 0}, {b.xmax - kIn, b.ymin + kIn, 0},
                             {b.xmax - kIn, b.ymax - kIn, 0}, {b.xmin + kIn, b.ymax - kIn, 0}};
    std::string why;
    for (const Pose2& c : corners) {
      if (!sim::FreePose(room, c, 0, &why)) return std::nullopt;
    }
    for (const sim::Segment& s : walls) {
      const sim::Box wall{std::min(s.a.x, s.b.x), std::min(s.a.y, s.b.y), std::max(s.a.x, s.b.x),
                          std::max(s.a.y, s.b.y)};
      if (wall.xmax > b.xmin + kIn && wall.xmin < b.xmax - kIn && wall.ymax > b.ymin + kIn &&
          wall.ymin < b.ymax - kIn)
        return std::nullopt;
      const double g = Gap(b, wall);
      // Far enough from the wall, or still against a wall it stood against (moved along it).
      if (g >= gap_m || (g < 1e-9 && Gap(was, wall) < 1e-9)) continue;
      return std::nullopt;
    }
  }
  return out;
}

std::string RelocMarkdown(const std::vector<RelocWorld>& worlds, const RelocOptions& ro,
                          const std::string& command) {
  std::ostringstream md;
  const bool mv = ro.move_m > 0;
  md << "# Relocalisation in a saved map: results\n\n"
     << "Generated by `" << command
     << "` (tests/tools/reloc_eval.h; docs/relocalization.md says how to read it). "
     << "Per world: one exploration mission makes the map (seed " << ro.seed << "), then "
     << ro.runs
     << " runs from random free start poses (uniform in the room, at least the robot radius + "
     << F(ro.clearance_extra_m * 100, 0)
     << " cm from walls and furniture, uniform heading) start from it, "
     << "each up to " << F(ro.max_time_s, 0) << " s robot time"
     << (mv ? "" : " and ending " + F(ro.after_commit_s, 0) + " s after the commit")
     << ". Errors are in the world frame through the least-squares fit of the "
        "first "
        "mission's map trajectory onto its true trajectory (fit residual below). *Confidently "
        "wrong*: committed "
        "more than "
     << F(ro.wrong_position_m * 100, 0) << " cm / " << F(ro.wrong_heading_rad * kDeg, 0)
     << "° off and not back within " << F(ro.recover_s, 0)
     << " s, or still off when the run ended. *Correct*: committed, never confidently wrong, "
        "within those bounds at the end.\n\n";
  if (mv) {
    md << "Moved furniture: before each run one piece the saved map modelled (a piece: the world's boxes "
          "that touch, as an L-shaped desk; column *piece moved* lists its boxes) was moved by "
       << F(ro.move_m, 2) << " m along x or y (seeded; to a place inside the room at least "
       << F(ro.move_gap_m, 2)
       << " m from every other piece and from the walls, or still against the wall it stood against); "
          "the runs then clean until done or the time limit (the robot has to pass the piece). *Move noted*: "
          "the saved map's object for the piece ends with a \"moved ...\" note. *Model updated*: that object "
          "(same id) ends within "
       << F(ro.moved_match_m * 100, 0)
       << " cm of the piece's new centre, and no object is left within that of the old one. *Others "
          "disturbed*: saved objects that did not move but end noted \"moved ...\" or gone from the map "
          "(false reports; runs that never committed explore afresh and are not counted), and in how many runs.\n\n";
  }
  md << "| world | map | fit rms cm | runs | committed | correct | confidently wrong | time to "
        "relocalise s median | "
        "worst | error at commit cm median / max | heading at commit deg max | max error after "
        "(from commit + 5 s) "
        "cm / deg | saved ids kept | duplicate lines |"
     << (mv ? " pieces moved | move noted | model updated | others disturbed (runs) |" : "") << "\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|" << (mv ? "---|---|---|---|" : "") << "\n";
  for (const RelocWorld& w : worlds) {
    int committed = 0, correct = 0, wrong = 0, kept = 0, saved = 0, dups = 0, moves = 0, noted = 0,
        updated = 0, disturbed = 0, disturbed_runs = 0;
    std::vector<double> times, at_commit;
    double heading_max = 0, after_m = 0, after_deg = 0, at_commit_max = 0;
    bool any_after = false;
    for (const RelocRun& r : w.runs) {
      committed += r.committed;
      correct += r.correct;
      wrong += r.confidently_wrong;
      kept += r.kept_ids;
      saved += r.saved_lines;
      dups += r.duplicates;
      moves += r.moved.world_index >= 0;
      noted += r.moved.noted;
      updated += r.moved.updated;
      disturbed += r.moved.others_disturbed;
      disturbed_runs += r.moved.others_disturbed > 0;
      if (!r.committed) continue;
      times.push_back(r.relocalize_s);
      at_commit.push_back(r.at_commit.position_m * 100);
      at_commit_max = std::max(at_commit_max, r.at_commit.position_m * 100);
      heading_max = std::max(heading_max, r.at_commit.heading_rad * kDeg);
      if (!r.after_sampled) continue;
      any_after = true;
      after_m = std::max(after_m, r.max_after.position_m * 100);
      after_deg = std::max(after_deg, r.max_after.heading_rad * kDeg);
    }
    const size_t n = w.runs.size();
    const auto pct = [n](int k) { return std::to_string(k) + "/" + std::to_string(n); };
    const bool any = !times.empty();
    md << "| " << w.world << " | " << (w.map_done ? "done" : "not done") << ", " << w.map_lines
       << " lines, " << w.map_objects << " objects | " << F(w.fit_rms_m * 100) << " | " << n
       << " | " << pct(committed) << " | " << pct(correct) << " | " << wrong << " | "
       << (any ? F(Quantile(times, 0.5)) : "-") << " | " << (any ? F(Quantile(times, 1.0)) : "-")
       << " | " << (any ? F(Quantile(at_commit, 0.5)) + " / " + F(at_commit_max) : "-") << " | "
       << (any ? F(heading_max) : "-") << " | "
       << (any_after ? F(after_m) + " / " + F(after_deg) : "-") << " | " << kept << "/" << saved
       << " | " << dups << " |";
    if (mv)
      md << " " << moves << " | " << noted << "/" << moves << " | " << updated << "/" << moves << " | " << disturbed
         << " (" << disturbed_runs << ") |";
    md << "\n";
  }
  md << "\n## Every run\n\n"
     << "| world | seed | start (world) | end | committed at s (time to relocalise) | hypotheses | "
        "attempts | error at commit cm / deg | "
        "final error cm / deg | confidently wrong | ids kept | duplicates |"
     << (mv ? " piece moved (world index: saved id, by) | noted | updated | its box centre at the end | others disturbed |"
            : "")
     << "\n|---|---|---|---|---|---|---|---|---|---|---|---|" << (mv ? "---|---|---|---|---|" : "") << "\n";
  for (const RelocWorld& w : worlds) {
    for (const RelocRun& r : w.runs) {
      md << "| " << w.world << " | " << r.seed << " | " << F(r.start.x, 2) << ", "
         << F(r.start.y, 2) << ", " << F(r.start.theta * kDeg, 0) << "° | " << r.end_state << " at "
         << F(r.end_t) << " s | "
         << (r.committed ? F(r.commit_t) + " (" + F(r.relocalize_s) + ")" : "-") << " | "
         << (r.committed ? std::to_string(r.hypotheses) : "-") << " | " << r.attempts << " | "
         << (r.committed
                 ? F(r.at_commit.position_m * 100) + " / " + F(r.at_commit.heading_rad * kDeg)
                 : "-")
         << " | "
         << (r.committed
                 ? F(r.final_error.position_m * 100) + " / " + F(r.final_error.heading_rad * kDeg)
                 : "-")
         << " | " << (r.confidently_wrong ? "yes" : "no") << " | " << r.kept_ids << "/"
         << r.saved_lines << " | " << r.duplicates << " |";
      if (mv) {
        const RelocRun::Moved& m = r.moved;
        if (m.world_index < 0) {
          md << " none could be moved | - | - | - | - |";
        } else {
          std::string boxes;
          for (size_t k : m.boxes) {
            if (!boxes.empty()) boxes += '+';
            boxes += std::to_string(k);
          }
          md << " " << boxes << ": " << m.saved_id << ", " << F(m.dx, 2) << ", " << F(m.dy, 2) << " | "
             << (m.noted ? "yes" : "no") << " | " << (m.updated ? "yes" : "no") << " | " << m.box << " | "
             << m.others_disturbed << " |";
        }
      }
      md << "\n";
    }
  }
  return md.str();
}

}  // namespace irslam::metrics
