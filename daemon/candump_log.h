// The candump -L log format, as written by can-utils' candump, irslam-candump and
// irslamd's bus recorder ([record]), read back by irslam-replay (contracts §7):
//   (1700000000.123456) vcan0 110#0102030405060708
// Pure text functions (no file, no clock). Lines starting with '#' are comments
// (can-utils' canplayer skips every line that does not start with '('); the
// recorder's first line is a comment header that carries the time origin and the
// time scale (RecordHeader).
#ifndef IRSLAM_DAEMON_CANDUMP_LOG_H_
#define IRSLAM_DAEMON_CANDUMP_LOG_H_

#include <linux/can.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace irslam {

struct LogLine {
  enum class Kind {
    kFrame,    // a classic CAN frame with a standard id: `frame` is set
    kForeign,  // a well-formed frame irslamd never reads (extended id, RTR, CAN FD)
    kComment,  // '#' ... (header, notes)
    kBlank,
  };
  Kind kind = Kind::kBlank;
  int64_t stamp_ns = 0;  // the log's time stamp (CLOCK_REALTIME for candump)
  std::string iface;
  can_frame frame{};
};

// The longest line accepted (a CAN FD line is under 160 characters).
inline constexpr size_t kMaxLogLineBytes = 512;

// Parses one line (without its newline; a trailing '\r' is allowed). False with a
// short reason in *error ("bad time stamp", ...) on a malformed line.
bool ParseLogLine(std::string_view line, LogLine* out, std::string* error);

// One line in candump -L format, stamped with stamp_ns (printed to the microsecond).
std::string FormatLogLine(int64_t stamp_ns, std::string_view iface, const can_frame& frame);

// irslamd's recorder header: "# irslamd-record v1 origin=SEC.NANOS time_scale=K period_s=P"
// origin: the CLOCK_REALTIME instant of the daemon's robot time 0; time_scale: robot
// seconds per wall second; period_s: the control period (robot time).
struct RecordHeader {
  int64_t origin_ns = 0;
  double time_scale = 1;
  double period_s = 0.02;
};
std::string FormatRecordHeader(const RecordHeader& h);
// An API call the recorder notes between the frames, as a comment (canplayer skips
// it): "# irslamd-event (SEC.MICROS) start" (or stop) at the daemon's robot time of
// the call, in the same stamps as the frames.
struct LogEvent {
  int64_t stamp_ns = 0;
  std::string name;  // "start" (explore), "start_clean", "stop"
};
std::string FormatEventComment(int64_t stamp_ns, std::string_view name);
std::optional<LogEvent> ParseEventComment(std::string_view comment);

// Robot time from log time: ns since the origin, times the time scale. irslamd takes
// its robot time the same way from whole microseconds of wall time, and its recorder
// writes those microseconds, so the replay gives the core the very same numbers.
inline double RobotTimeFromLogNs(int64_t ns_since_origin, double time_scale) {
  return static_cast<double>(ns_since_origin) * 1e-9 * time_scale;
}
// The header in a comment line (with its leading '#'); nullopt if it is another comment.
std::optional<RecordHeader> ParseRecordHeader(std::string_view comment);

}  // namespace irslam

#endif  // IRSLAM_DAEMON_CANDUMP_LOG_H_
