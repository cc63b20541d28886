// Grid path planning for the go-to behaviour: A* (8-connected) on an occupancy
// grid made from the mapped lines and any extra obstacle points (IR readings),
// inflated by the robot radius plus a clearance. Pure.
//
// PathPlanner keeps its grids between calls (issue 15): no allocation once the
// grid's size is known, the clearance grid reused while the obstacles and the
// grid are the same, the heuristic's distances (hypot) tabulated by cell offset,
// and a goal the last failed search from the same start cell could not reach is
// answered at once (a failed A* visits every reachable cell: that set is kept).
// The search itself is unchanged: the same paths as before, cell for cell.
#ifndef IRSLAM_CONTROL_PATH_PLANNER_H_
#define IRSLAM_CONTROL_PATH_PLANNER_H_

#include <Eigen/Core>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>
#include <optional>
#include <vector>

#include "control/quad_heap.h"
#include "types/options.h"

namespace irslam::control {

struct PlannerOptions {
  double resolution_m = 0.05;
  double inflation_m = 0.25;  // robot radius + clearance
  double hard_m = 0.19;       // never closer than this (robot radius + a little): near the
                              // start, cells between hard_m and inflation_m may be crossed
                              // to get out of a tight spot, and cells within hard_m only
                              // moving away from the obstacle
  double margin_m = 1.0;      // grid extends this far beyond the obstacles
};
// The planner's configurable keys (resolution and margin; the go-to sets the
// inflation and hard distance from the robot radius and its clearances, so they
// are no keys). Section [exploration], as planner_*.
options::Table<PlannerOptions> PlannerKeys();

struct Obstacle {
  Eigen::Vector2d a, b;  // a segment (a == b: a point)
};

// The point of the obstacle nearest p.
Eigen::Vector2d ClosestPoint(const Obstacle& o, const Eigen::Vector2d& p);

// A path from start to goal (both included), simplified to its corners; nullopt if
// the goal cannot be reached. A start inside the inflation, even within hard_m,
// is allowed (the robot may stand closer to a wall than the clearance, or where
// a mapped side, extended past its seen ends, is assumed to go on).
std::optional<std::vector<Eigen::Vector2d>> PlanPath(const std::vector<Obstacle>& obstacles,
                                                     const Eigen::Vector2d& start,
                                                     const Eigen::Vector2d& goal,
                                                     const PlannerOptions& options);

// The same, keeping its buffers and caches between calls (one per go-to), and
// able to run a search in pieces (issue 15): Start() prepares it (the grid and
// the checks that answer at once), Continue() runs it for at most a number of
// queue pops, so a caller can spread a search over control periods. A search
// run in pieces finds exactly the path the one-shot Plan() finds.
class PathPlanner {
 public:
  enum class Progress { kRunning, kFound, kFailed };

  std::optional<std::vector<Eigen::Vector2d>> Plan(const std::vector<Obstacle>& obstacles,
                                                   const Eigen::Vector2d& start,
                                                   const Eigen::Vector2d& goal,
                                                   const PlannerOptions& options);
  // Starts a search (abandoning any search still running); kFound or kFailed
  // when it is answered without one (a goal off the grid or blocked, or known
  // unreachable).
  // The first n_static obstacles are static (mapped sides, contacts): their
  // clearance grid is kept while they are the same, and the rest (what the
  // sensors see now) is added to a copy of it.
  Progress Start(const std::vector<Obstacle>& obstacles, const Eigen::Vector2d& start,
                 const Eigen::Vector2d& goal, const PlannerOptions& options,
                 size_t n_static = static_cast<size_t>(-1));
  // Cells along this trail (points of the robot's own recent path, in order)
  // may be crossed whatever their clearance, by the searches started from now
  // on: the robot's body has been there. A robot that drove into a pocket the
  // map closes (a side seen short and planned round extended past its end)
  // finds its way out the way it came. Consecutive points farther apart than
  // max_step_m (a jump of the pose) break the trail. Empty: none (the default).
  void SetFreeTrail(const std::vector<Eigen::Vector2d>& trail, double max_step_m = 0.3);
  // Runs the search started for at most max_pops pops (adds them to *pops).
  Progress Continue(int64_t max_pops, int64_t* pops);
  bool running() const { return running_; }
  // The clearance cells the last Start computed (filled, or the distance to
  // an obstacle evaluated): its work, bar the search.
  int64_t start_cells() const { return start_cells_; }
  // The path found by the last search that ended kFound.
  const std::vector<Eigen::Vector2d>& path() const { return path_; }
  struct Stats {
    uint64_t plans = 0;         // calls
    uint64_t searches = 0;      // A* searches run
    uint64_t failed = 0;        // calls that found no path
    uint64_t known_unreachable = 0;  // ... answered from the last failed search
    uint64_t clearance_reused = 0;   // calls that reused the clearance grid
    uint64_t static_clearance_reused = 0;  // ... that reused only the static obstacles' part
    uint64_t pops = 0;          // A* queue pops, all searches
    uint64_t max_pops = 0;      // ... the longest search's
  };
  const Stats& stats() const { return stats_; }

 private:
  struct Geometry {
    Eigen::Vector2d lo = Eigen::Vector2d::Zero();
    int nx = 0, ny = 0;
    double res = 0;
    bool operator==(const Geometry& o) const {
      return lo == o.lo && nx == o.nx && ny == o.ny && res == o.res;
    }
  };
  // The search in progress: A* from cell s_ to goal_i_ with the options o_.
  bool SearchSome(int64_t max_pops, int64_t* pops);  // true once it has ended
  Progress Finish();
  double H(int dx, int dy);
  void UpdateClearances(const std::vector<Obstacle>& obstacles, size_t n_static, const Geometry& geo,
                        double inflation_m);
  void GrowHypot(int nx, int ny);

  // Marks the trail's cells (3 x 3 round each point, the points joined every
  // half cell) with the search's stamp gen_ in trail_mark_.
  void MarkTrail();
  bool OnTrail(int j) const { return !trail_.empty() && trail_mark_[static_cast<size_t>(j)] == gen_; }

  Geometry geo_;
  std::vector<Eigen::Vector2d> trail_;  // SetFreeTrail's, broken at jumps: pieces end at a NaN point
  std::vector<uint32_t> trail_mark_;    // per cell (row-major): gen_ when on the trail
  std::vector<Obstacle> obstacles_;   // the static obstacles fixed_clear_ was made from
  std::vector<Obstacle> transient_;   // ... and the transient ones clear_ adds
  double clear_inflation_m_ = -1;
  std::vector<float> fixed_clear_;    // the static obstacles' clearances (if fixed_valid_)
  bool fixed_valid_ = false;
  std::vector<float> clear_;          // all obstacles'

  // Per cell, valid where its stamp holds the search's number gen_ (so a search
  // starts without filling them): its cost and predecessor. The arrays come
  // from calloc, whose large blocks are pages the kernel supplies as they are
  // first written: a grid that grows costs page faults only where a search
  // goes (the first plan in a 16 x 12 m room touched ~5 MB in one period).
  struct FreeDeleter {
    void operator()(void* p) const { std::free(p); }
  };
  template <typename T>
  struct LazyArray {
    std::unique_ptr<T[], FreeDeleter> p;
    size_t n = 0;
    void Reserve(size_t size) {
      if (size <= n) return;
      p.reset(static_cast<T*>(std::calloc(size, sizeof(T))));
      if (!p) throw std::bad_alloc();
      n = size;
    }
    T& operator[](size_t i) { return p[i]; }
    const T& operator[](size_t i) const { return p[i]; }
  };
  // A cell's search state, one struct (one cache line for the three), stored
  // in tiles of 16 x 16 cells (4 KB, one page) rather than row by row: a
  // search spreads in 2-D blobs, and a blob of cells lies in few pages and
  // cache lines. The cells keep their row-major numbers (i = y nx + x) in the
  // open list and in from, so the search and its ties are unchanged.
  struct CellState {
    double g;
    int32_t from;
    uint32_t stamp;
  };
  static constexpr int kTileBits = 4;  // tiles of 16 x 16
  static constexpr int kTileMask = (1 << kTileBits) - 1;
  static size_t Tiled(int x, int y, int tiles_x) {
    return ((static_cast<size_t>(y >> kTileBits) * static_cast<size_t>(tiles_x) +
             static_cast<size_t>(x >> kTileBits))
            << (2 * kTileBits)) +
           static_cast<size_t>(((y & kTileMask) << kTileBits) + (x & kTileMask));
  }
  static int Tiles(int n) { return (n + kTileMask) >> kTileBits; }
  LazyArray<CellState> cells_;
  int tiles_x_ = 0;  // the grid's width in tiles
  uint32_t gen_ = 0;
  CellState& Cell(int x, int y) { return cells_[Tiled(x, y, tiles_x_)]; }
  const CellState& Cell(int x, int y) const { return cells_[Tiled(x, y, tiles_x_)]; }
  // hypot(|dx|, |dy|) by offset, 0: not computed yet (bar 0, 0); tiled likewise.
  LazyArray<double> hypot_;
  int hypot_tiles_x_ = 0;
  double G(int x, int y) const {
    const CellState& c = Cell(x, y);
    return c.stamp == gen_ ? c.g : 1e18;
  }
  int From(int i) const {
    const CellState& c = Cell(i % geo_.nx, i / geo_.nx);
    return c.stamp == gen_ ? c.from : -1;
  }
  QuadHeap open_;  // (f, cell): pops in std::priority_queue's order
  int hypot_nx_ = 0, hypot_ny_ = 0;
  // The last failed search: from this start cell on this clearance grid, the
  // cells with a finite cost were all that can be reached.
  bool failed_valid_ = false;
  int failed_start_ = -1;
  double failed_hard_m_ = 0;
  Stats stats_;
  bool running_ = false;
  uint64_t search_pops_ = 0;  // the search in progress so far
  int64_t start_cells_ = 0;
  int s_ = 0, goal_i_ = 0, sx_ = 0, sy_ = 0, gx_ = 0, gy_ = 0;
  PlannerOptions o_;
  Eigen::Vector2d start_ = Eigen::Vector2d::Zero(), goal_ = Eigen::Vector2d::Zero();
  std::vector<Eigen::Vector2d> path_;
};

// Whether a path (from the robot's position) still keeps at least `clearance_m`
// from every obstacle, beyond its first `skip_m` (where the robot stands now).
bool PathClear(const std::vector<Obstacle>& obstacles, const std::vector<Eigen::Vector2d>& path,
               double clearance_m, double skip_m);

// The length of a polyline.
double PathLength(const std::vector<Eigen::Vector2d>& path);

}  // namespace irslam::control

#endif  // IRSLAM_CONTROL_PATH_PLANNER_H_
