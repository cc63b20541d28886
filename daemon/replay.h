// Replay: a recorded bus (candump -L: irslamd's [record], irslam-candump, can-utils'
// candump) fed through the same robot::RobotCore offline, as fast as the CPU allows,
// to reproduce the map the daemon made (irslam-replay, contracts §7). Pure: lines in,
// map and counts out.
//
// What the log carries and how each part is used (docs/replay.md):
//   - the controller's frames (CTRL_STATUS, ENCODER, IR_A/B): OnFrame at their log
//     time. SLAM takes its time from the controller's stamps inside the frames, so
//     the same frames in the same order give the same lines and pose, bit for bit;
//   - irslamd's WHEEL_CMD, sent once per control period right after Tick: each one
//     is a Tick of the replayed core at its log time (the daemon's tick grid);
//   - irslamd's recorder notes the `start` and `stop` calls as comments at their
//     exact time (OnEvent), and the stop call's immediate stop frame (not a tick)
//     follows the note. Other logs have no room for API calls: a WHEEL_CMD with
//     Enable=1 (or a DAEMON_HEARTBEAT with a driving state) while the replayed
//     mission is idle or done means start was called since the previous tick:
//     Start, then Tick. A heartbeat saying idle while the replayed mission drives:
//     Stop (the stop frame itself, which cannot be told from a tick that came
//     early after a late one, is replayed as a tick).
// The replayed core's own WHEEL_CMD is compared with the recorded one at every tick
// (Enable, and the velocities within 1 mm/s; not Seq), and its state with every recorded heartbeat: the
// counts say how faithfully the mission was reproduced.
#ifndef IRSLAM_DAEMON_REPLAY_H_
#define IRSLAM_DAEMON_REPLAY_H_

#include <climits>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "daemon/candump_log.h"
#include "robot/robot_core.h"

namespace irslam {

struct ReplayStats {
  uint64_t frames = 0;             // controller frames fed to the core
  uint64_t ticks = 0;              // control periods replayed (recorded WHEEL_CMDs)
  uint64_t stop_frames = 0;        // recorded stop frames (not ticks)
  uint64_t starts = 0;             // start calls derived from the daemon's frames
  uint64_t stops = 0;              // stop calls derived from the daemon's frames
  uint64_t commands_matched = 0;   // replayed WHEEL_CMD as recorded (Enable, velocities ±1 mm/s)
  uint64_t commands_differed = 0;
  uint64_t heartbeats = 0;
  uint64_t states_differed = 0;    // recorded heartbeat state != replayed state
  uint64_t ignored = 0;            // frames of other ids, extended/FD frames
  uint64_t skipped = 0;            // controller frames before the daemon was there
  double first_t = 0, last_t = 0;  // robot time span of the log
  std::optional<double> started_t;  // robot time of the first start
  std::string start_error;          // a derived start the core refused (why)
};

class Replay {
 public:
  // time_scale: robot seconds per second of log time; origin_ns: the log time of
  // robot time 0 (irslamd's header, else the first frame's stamp).
  Replay(robot::CoreOptions core, int64_t origin_ns, double time_scale);

  // One frame line of the log (LogLine::Kind::kFrame / kForeign); others are ignored.
  void Feed(const LogLine& line);
  // A bystander's log (no recorder header) may begin long before the daemon did:
  // controller frames stamped before ns are not fed (the daemon was not there).
  void SkipControllerFramesBefore(int64_t ns) { skip_before_ns_ = ns; }
  // An API call irslamd's recorder noted (start, stop): replayed at its exact time.
  // From the first note on, start and stop are no longer derived. Others are ignored.
  void OnEvent(const LogEvent& event);
  // The log comes from irslamd's recorder (its header): start and stop are noted,
  // never derived.
  void SetNoted() { noted_ = true; }

  const robot::RobotCore& core() const { return core_; }
  const ReplayStats& stats() const { return stats_; }

 private:
  static bool Driving(control::MissionState s);
  void OnWheelCmd(const can_frame& f, double t);
  void OnHeartbeat(const can_frame& f, double t);
  void StartMission(double t);

  robot::RobotCore core_;
  int64_t origin_ns_;
  double time_scale_;
  ReplayStats stats_;
  bool any_ = false;
  int64_t skip_before_ns_ = INT64_MIN;
  bool noted_ = false;            // the log notes start and stop (irslamd's recorder)
  bool stop_frame_next_ = false;  // a noted stop: its stop frame follows
};

// The time scale of a log without irslamd's header, from the controller's own clock:
// each ENCODER frame carries the controller's millisecond stamp (robot time, 16 bits,
// wrapping every 65.536 s), the log the time it was received. Robot time against log
// time is a line of slope 1 / scale plus a receive latency that a loaded machine makes
// bursty but which does not grow with the log; a least-squares line over many frames
// has it to within latency / span. The stamps are unwrapped frame to frame; a step back
// or a jump of more than 1 s (a controller reset, a reordered or lost stretch) begins a
// new segment, and the segments share one slope (pooled within-segment least squares),
// so a reset costs nothing but its frame. Add() the frames in log order; Scale() is
// nullopt until at least 100 frames span 1 s of robot time, else rounded as
// EstimateTimeScale's.
class ControllerClockFit {
 public:
  void Add(int64_t log_ns, uint16_t stamp_ms);
  std::optional<double> Scale() const;
  // The fitted scale before rounding (nullopt as Scale()).
  std::optional<double> Measured() const;
  size_t frames() const { return frames_; }

 private:
  // Adds the open segment's centred sums and span (none under two frames).
  void AddOpenSegment(double* cxx, double* cxy, double* span) const;
  void CloseSegment();
  // The open segment: sums of x = robot s, y = log s, both from its first frame.
  double sx_ = 0, sy_ = 0, sxx_ = 0, sxy_ = 0;
  size_t n_ = 0;
  int64_t first_ns_ = 0;
  double robot_s_ = 0;  // unwrapped, from the segment's first frame
  uint16_t last_ms_ = 0;
  // Closed segments: their centred sums.
  double cxx_ = 0, cxy_ = 0, span_s_ = 0;
  size_t frames_ = 0;
};

// The scale k rounded to one significant digit (1, 2, 5, 10, ...) when that is within
// 3 % of it, else to two.
double RoundTimeScale(double k);

// The time scale of a log without irslamd's header, from its WHEEL_CMD stamps (one
// per control period of period_s robot seconds, on an absolute clock; a loaded
// machine skips periods): the period is the median over windows of 10 spacings of
// window / the whole number of periods in it (counted with the mean of the spacings
// under 1.5 median spacings), and
// the scale is period_s over it, rounded to one significant digit when that is within
// 3 %, else to two. nullopt with fewer than 11 commands. A loaded machine's bursts
// of receive stamps distort it (docs/replay.md): ControllerClockFit first.
std::optional<double> EstimateTimeScale(const std::vector<int64_t>& wheel_cmd_stamps_ns, double period_s);

}  // namespace irslam

#endif  // IRSLAM_DAEMON_REPLAY_H_
