// BusRecorder: irslamd records its own bus ([record], docs/replay.md) in candump -L
// format, for irslam-replay at the desk: every frame the daemon received and every
// frame it sent, in the order the core saw them, stamped with the daemon's own robot
// time (as CLOCK_REALTIME, to the microsecond), under a header comment with the time
// origin and scale (daemon/candump_log.h).
//
// Record() runs on the control loop and never blocks on the disk: it formats the line
// into a bounded buffer under a mutex; a writer thread empties the buffer to
// STATE_DIR/bus.log and rotates it (bus.log.1 .. bus.log.N-1, oldest last) at
// max_bytes. A full buffer drops lines and counts them. A file that cannot be
// written stops the recording (one log line, counted), never the daemon.
#ifndef IRSLAM_DAEMON_BUS_RECORDER_H_
#define IRSLAM_DAEMON_BUS_RECORDER_H_

#include <linux/can.h>

#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>

#include "daemon/candump_log.h"
#include "daemon/daemon_settings.h"

namespace irslam {

struct RecorderStats {
  uint64_t lines = 0;           // lines written to the files
  uint64_t dropped = 0;         // lines dropped (buffer full, or after a write error)
  uint64_t bytes = 0;           // bytes in the present file
  uint64_t rotations = 0;
  std::string path;
  std::string error;            // the write error that stopped the recording
};

class BusRecorder {
 public:
  // iface: the name written on every line (candump's interface column).
  BusRecorder(std::string state_dir, RecordSettings settings, RecordHeader header, std::string iface);
  ~BusRecorder();  // writes what is buffered, then stops the thread
  BusRecorder(const BusRecorder&) = delete;
  BusRecorder& operator=(const BusRecorder&) = delete;

  // Rotates a previous run's bus.log away, opens a new one and starts the writer.
  bool Open(std::string* error);
  // A frame at the daemon's robot time t_s (the time the core was given).
  void Record(const can_frame& frame, double t_s);
  // An API call (start, stop) at the daemon's robot time t_s, as an event comment.
  void Note(std::string_view event, double t_s);
  // Writes what is buffered and stops the writer (the destructor does it too).
  void Close();
  RecorderStats stats() const;

 private:
  void Append(std::string line);
  int64_t StampNs(double t_s) const;
  void WriterLoop();
  bool OpenFile(std::string* error);  // the header first
  bool Rotate(std::string* error);
  bool WriteAll(const std::string& text, std::string* error);

  const std::string dir_, path_;
  const RecordSettings settings_;
  const RecordHeader header_;
  const std::string iface_;
  int fd_ = -1;  // writer thread only (after Open)
  bool file_has_lines_ = false;  // writer thread only
  mutable std::mutex mu_;
  std::condition_variable wake_;
  std::string pending_;  // guarded by mu_
  bool stopping_ = false;
  bool failed_ = false;
  RecorderStats stats_;  // guarded by mu_
  std::thread writer_;
};

}  // namespace irslam

#endif  // IRSLAM_DAEMON_BUS_RECORDER_H_
