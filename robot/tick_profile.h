// The per-period work budget, made visible (issue 15): a fixed-bucket histogram
// of each control period's work (p50/p99/p99.9/max in bounded memory) and, per
// phase, how much each period spent where. Pure: the shells (irslamd,
// `irslam-sim run`) measure durations around the core's calls with their own
// clock and add them here; the planning phase is measured through the clock the
// shell injects into the core (RobotCore::SetWorkClock).
#ifndef IRSLAM_ROBOT_TICK_PROFILE_H_
#define IRSLAM_ROBOT_TICK_PROFILE_H_

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <functional>

namespace irslam::robot {

// A clock in ns that the shell measures work with (monotonic or CPU time).
using WorkClockNs = std::function<int64_t()>;

// Durations in ns, 8 buckets per power of two (an upper edge at most 12.5 %
// above the value) from 64 ns to about 68 s; below and above go to the ends.
class DurationHistogram {
 public:
  static constexpr int kSub = 8;
  static constexpr int kMinLog2 = 6;   // 64 ns
  static constexpr int kMaxLog2 = 36;  // ~68.7 s
  static constexpr int kBuckets = (kMaxLog2 - kMinLog2) * kSub + 1;

  void Add(int64_t ns) {
    ns = std::max<int64_t>(ns, 0);
    ++counts_[static_cast<size_t>(Bucket(ns))];
    ++count_;
    max_ = std::max(max_, ns);
    sum_ += ns;
  }
  uint64_t count() const { return count_; }
  int64_t max() const { return max_; }
  double mean() const { return count_ ? static_cast<double>(sum_) / static_cast<double>(count_) : 0; }
  // The smallest bucket upper edge below which a fraction q of the values lie
  // (never above the largest value seen); 0 when empty.
  int64_t Quantile(double q) const {
    if (count_ == 0) return 0;
    const double want = q * static_cast<double>(count_);
    uint64_t seen = 0;
    for (int b = 0; b < kBuckets; ++b) {
      seen += counts_[static_cast<size_t>(b)];
      if (static_cast<double>(seen) >= want && seen > 0) return std::min(UpperEdge(b), max_);
    }
    return max_;
  }
  // The bucket of a duration, and its upper edge (exposed for the tests).
  static int Bucket(int64_t ns) {
    if (ns < (int64_t{1} << kMinLog2)) return 0;
    int log2 = 63 - __builtin_clzll(static_cast<unsigned long long>(ns));
    if (log2 >= kMaxLog2) return kBuckets - 1;
    const int sub = static_cast<int>((ns >> (log2 - 3)) & (kSub - 1));  // the 3 bits below the top one
    return 1 + (log2 - kMinLog2) * kSub + sub;
  }
  static int64_t UpperEdge(int b) {
    if (b == 0) return int64_t{1} << kMinLog2;
    if (b >= kBuckets - 1) return int64_t{1} << kMaxLog2;
    const int log2 = (b - 1) / kSub + kMinLog2, sub = (b - 1) % kSub;
    return (int64_t{1} << log2) + (static_cast<int64_t>(sub) + 1) * (int64_t{1} << (log2 - 3));
  }

 private:
  std::array<uint64_t, kBuckets> counts_{};
  uint64_t count_ = 0;
  int64_t max_ = 0;
  int64_t sum_ = 0;
};

// Where a control period's work went.
enum class TickPhase { kSlam, kMission, kPlanning, kMapSave, kOther, kCount };
inline const char* ToString(TickPhase p) {
  switch (p) {
    case TickPhase::kSlam: return "slam";          // frames since the last period: decoding, IR, SLAM
    case TickPhase::kMission: return "mission";    // the core's tick less the planning
    case TickPhase::kPlanning: return "planning";  // path planning inside the tick
    case TickPhase::kMapSave: return "map_save";   // the map's save (hand-over) and its rate limit
    case TickPhase::kOther: return "other";        // the rest of the shell's period (API, outputs)
    case TickPhase::kCount: break;
  }
  return "?";
}
inline constexpr int kNumTickPhases = static_cast<int>(TickPhase::kCount);

// One period's work by phase, ns.
struct TickWork {
  std::array<int64_t, kNumTickPhases> ns{};
  int64_t total() const {
    int64_t t = 0;
    for (int64_t v : ns) t += v;
    return t;
  }
  int64_t& operator[](TickPhase p) { return ns[static_cast<size_t>(p)]; }
  int64_t operator[](TickPhase p) const { return ns[static_cast<size_t>(p)]; }
};

// Every period's total in a histogram; per phase the maximum and the sum; the
// worst period kept whole (which phase took it).
class TickProfile {
 public:
  void Add(const TickWork& w, double robot_t) {
    const int64_t total = w.total();
    work_.Add(total);
    for (int p = 0; p < kNumTickPhases; ++p) {
      phase_max_[static_cast<size_t>(p)] = std::max(phase_max_[static_cast<size_t>(p)], w.ns[static_cast<size_t>(p)]);
      phase_sum_[static_cast<size_t>(p)] += w.ns[static_cast<size_t>(p)];
    }
    if (total >= worst_.total()) {
      worst_ = w;
      worst_t_ = robot_t;
    }
  }
  const DurationHistogram& work() const { return work_; }
  int64_t phase_max(TickPhase p) const { return phase_max_[static_cast<size_t>(p)]; }
  int64_t phase_sum(TickPhase p) const { return phase_sum_[static_cast<size_t>(p)]; }
  const TickWork& worst() const { return worst_; }
  double worst_t() const { return worst_t_; }
  // The phase that took most of the worst period.
  TickPhase worst_phase() const {
    int best = 0;
    for (int p = 1; p < kNumTickPhases; ++p) {
      if (worst_.ns[static_cast<size_t>(p)] > worst_.ns[static_cast<size_t>(best)]) best = p;
    }
    return static_cast<TickPhase>(best);
  }

 private:
  DurationHistogram work_;
  std::array<int64_t, kNumTickPhases> phase_max_{};
  std::array<int64_t, kNumTickPhases> phase_sum_{};
  TickWork worst_;
  double worst_t_ = 0;
};

}  // namespace irslam::robot

#endif  // IRSLAM_ROBOT_TICK_PROFILE_H_
