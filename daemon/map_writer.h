// Saves maps off the control thread (issue 15): the control loop hands over a
// job - an immutable snapshot of the map, not yet encoded - and never waits for
// the encoding, the comparison or the disk; one writer thread encodes it as
// JSON, compares it with the last map saved (an identical one is not written)
// and saves it (daemon/map_store.h: temporary file, fsync, rename, fsync of
// the directory), and posts the outcome back onto the control loop's
// io_context, where the completion handler runs.
//
// Hand-over, race-free by construction: the job's snapshot is captured by its
// encoder (both threads only read it, and only the writer encodes it); the
// last map saved is a shared_ptr<const StoredMap> (read-only on both threads);
// the one job slot is guarded by a mutex; the outcome travels back by value
// through boost::asio::post. Nothing else is shared. One job at a time: Submit
// is only called when !busy() (the map service keeps a newer one waiting).
//
// Memory (issue 15's RSS budget): a map's JSON is ~20,000 small heap blocks
// (~0.3 MB for a 300 s mission) and encoding it leaves ~0.1 MB strings behind.
// The maps a delivered outcome makes obsolete (the previous map saved, or an
// encoded map that was not kept) go back to the writer thread to be freed
// there, off the control thread, and after each job and each such batch the
// writer returns the heap's free pages to the kernel (malloc_trim): without
// it they stay resident (measured: 0.5 MB of free heap at the end of a Fig. 14
// mission).
#ifndef IRSLAM_DAEMON_MAP_WRITER_H_
#define IRSLAM_DAEMON_MAP_WRITER_H_

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>
#include <condition_variable>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "daemon/map_store.h"

namespace irslam {

// A map to save, taken on the control thread as an immutable snapshot: calling
// it builds the map's JSON (contracts §4). Callable from any thread.
using MapEncoder = std::function<nlohmann::json()>;

class MapWriter {
 public:
  struct Job {
    MapEncoder encode;
    uint64_t seq = 0;     // the file's number if it is written
    std::string reason;
    std::shared_ptr<const StoredMap> last;  // the last map saved (or loaded): an identical one is not written
    bool may_write = true;  // false: a changed map is not written (too soon), only reported
  };
  enum class Result { kSaved, kUnchanged, kNotWritten, kFailed };
  struct Outcome {
    std::shared_ptr<const StoredMap> map;  // what was encoded (written, or tried)
    Result result = Result::kFailed;
    std::string error;  // when kFailed
    double ms = 0;      // encoding, comparing and writing
  };
  using Done = std::function<void(Outcome)>;

  // The job done on the calling thread: encode, compare, write (if changed and may_write).
  static Outcome Process(MapStore& store, const Job& job);

  // done runs on io (the control thread) once per submitted write.
  MapWriter(boost::asio::io_context& io, std::string dir, Done done);
  // Finishes the write in flight (its outcome is not delivered) and joins.
  ~MapWriter();
  MapWriter(const MapWriter&) = delete;
  MapWriter& operator=(const MapWriter&) = delete;

  // Control thread. Returns at once; requires !busy().
  void Submit(Job job);
  // Control thread: a write was submitted and its outcome not yet delivered.
  bool busy() const { return busy_; }
  // Control thread, at shutdown only: blocks until the write in flight is done
  // and returns its outcome (delivered here instead of through io); nullopt if
  // none was in flight.
  std::optional<Outcome> Drain();

 private:
  using WorkGuard = boost::asio::executor_work_guard<boost::asio::io_context::executor_type>;
  using Garbage = std::vector<std::shared_ptr<const StoredMap>>;
  void Loop();
  void Run(uint64_t id, Job job);  // writer thread: one job, its outcome posted
  // Control thread: the outcome to done_, then what it made obsolete (the job's
  // last map, and the encoded map if done_ did not keep it) back to the writer.
  void Deliver(uint64_t id, Outcome outcome, std::shared_ptr<const StoredMap> last);
  void Dispose(Garbage garbage);  // control thread: freed on the writer thread

  boost::asio::io_context& io_;
  Done done_;
  std::shared_ptr<int> alive_ = std::make_shared<int>(0);  // posted outcomes check it
  bool busy_ = false;          // control thread only
  uint64_t next_id_ = 0;       // control thread only
  uint64_t drained_id_ = 0;    // control thread only: an outcome Drain already delivered
  std::optional<WorkGuard> work_;  // control thread only: io keeps running while a write is in flight

  std::mutex mu_;
  std::condition_variable cv_;
  std::optional<std::pair<uint64_t, Job>> job_;  // guarded by mu_: submitted (id, job), not yet taken
  std::optional<std::pair<uint64_t, Outcome>> result_;  // guarded by mu_: the last outcome
  Garbage garbage_;                      // guarded by mu_: to be freed on the writer thread
  bool writing_ = false;                 // guarded by mu_
  bool quit_ = false;                    // guarded by mu_
  MapStore store_;                       // writer thread only (after construction)
  std::thread thread_;                   // last: started when everything above exists
};

}  // namespace irslam

#endif  // IRSLAM_DAEMON_MAP_WRITER_H_
