// Fixed-period scheduling without drift: deadlines stay on the grid
// start + n * period whatever the wake-up lateness; missed periods are counted as
// overruns and skipped (never bunched up). Pure: times are arguments (ns).
#ifndef IRSLAM_DAEMON_PERIOD_SCHEDULER_H_
#define IRSLAM_DAEMON_PERIOD_SCHEDULER_H_

#include <algorithm>
#include <cstdint>

namespace irslam {

class PeriodScheduler {
 public:
  PeriodScheduler(int64_t period_ns, int64_t start_ns)
      : period_ns_(period_ns), deadline_ns_(start_ns + period_ns) {}

  int64_t deadline_ns() const { return deadline_ns_; }
  int64_t period_ns() const { return period_ns_; }

  // Called when the timer for deadline_ns() fired at now_ns (now_ns >= deadline).
  // Records the lateness and moves to the next deadline on the grid.
  void OnWake(int64_t now_ns) {
    const int64_t late = std::max<int64_t>(0, now_ns - deadline_ns_);
    ++ticks_;
    last_late_ns_ = late;
    max_late_ns_ = std::max(max_late_ns_, late);
    sum_late_ns_ += late;
    deadline_ns_ += period_ns_;
    if (now_ns >= deadline_ns_) {
      // Woke a whole period (or more) late: skip the missed deadlines.
      const int64_t missed = (now_ns - deadline_ns_) / period_ns_ + 1;
      overruns_ += missed;
      deadline_ns_ += missed * period_ns_;
    }
  }
  // (Work that runs past the next deadline shows as a late wake-up there, and is
  // counted as an overrun then.)
  uint64_t ticks() const { return ticks_; }
  uint64_t overruns() const { return overruns_; }
  int64_t max_late_ns() const { return max_late_ns_; }
  int64_t last_late_ns() const { return last_late_ns_; }
  double mean_late_ns() const {
    return ticks_ ? static_cast<double>(sum_late_ns_) / static_cast<double>(ticks_) : 0.0;
  }
  void ResetStats() {
    ticks_ = overruns_ = 0;
    max_late_ns_ = sum_late_ns_ = last_late_ns_ = 0;
  }

 private:
  int64_t period_ns_;
  int64_t deadline_ns_;
  uint64_t ticks_ = 0;
  uint64_t overruns_ = 0;
  int64_t max_late_ns_ = 0;
  int64_t sum_late_ns_ = 0;
  int64_t last_late_ns_ = 0;
};

}  // namespace irslam

#endif  // IRSLAM_DAEMON_PERIOD_SCHEDULER_H_
