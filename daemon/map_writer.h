// Writes map files off the control thread (issue 15): the control loop hands
// over an immutable snapshot and never waits for the disk; one writer thread
// encodes and saves it (daemon/map_store.h: temporary file, fsync, rename,
// fsync of the directory) and posts the outcome back onto the control loop's
// io_context, where the completion handler runs.
//
// Hand-over, race-free by construction: the snapshot is a
// shared_ptr<const StoredMap> (both threads only read it); the one job slot is
// guarded by a mutex; the outcome travels back by value through
// boost::asio::post. Nothing else is shared. One write at a time: Submit is
// only called when !busy() (the map service keeps a newer map pending).
#ifndef IRSLAM_DAEMON_MAP_WRITER_H_
#define IRSLAM_DAEMON_MAP_WRITER_H_

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "daemon/map_store.h"

namespace irslam {

class MapWriter {
 public:
  struct Outcome {
    std::shared_ptr<const StoredMap> map;  // what was written (or tried)
    bool ok = false;
    std::string error;  // when !ok
    double ms = 0;      // encoding + writing, on the writer thread
  };
  using Done = std::function<void(Outcome)>;

  // done runs on io (the control thread) once per submitted write.
  MapWriter(boost::asio::io_context& io, std::string dir, Done done);
  // Finishes the write in flight (its outcome is not delivered) and joins.
  ~MapWriter();
  MapWriter(const MapWriter&) = delete;
  MapWriter& operator=(const MapWriter&) = delete;

  // Control thread. Returns at once; requires !busy().
  void Submit(std::shared_ptr<const StoredMap> map);
  // Control thread: a write was submitted and its outcome not yet delivered.
  bool busy() const { return busy_; }
  // Control thread, at shutdown only: blocks until the write in flight is done
  // and returns its outcome (delivered here instead of through io); nullopt if
  // none was in flight.
  std::optional<Outcome> Drain();

 private:
  using WorkGuard = boost::asio::executor_work_guard<boost::asio::io_context::executor_type>;
  struct Job {
    std::shared_ptr<const StoredMap> map;
    uint64_t id = 0;
  };
  void Loop();
  void Deliver(uint64_t id, Outcome outcome);  // control thread

  boost::asio::io_context& io_;
  Done done_;
  std::shared_ptr<int> alive_ = std::make_shared<int>(0);  // posted outcomes check it
  bool busy_ = false;          // control thread only
  uint64_t next_id_ = 0;       // control thread only
  uint64_t drained_id_ = 0;    // control thread only: an outcome Drain already delivered
  std::optional<WorkGuard> work_;  // control thread only: io keeps running while a write is in flight

  std::mutex mu_;
  std::condition_variable cv_;
  std::optional<Job> job_;               // guarded by mu_: submitted, not yet taken
  std::optional<std::pair<uint64_t, Outcome>> result_;  // guarded by mu_: the last outcome
  bool writing_ = false;                 // guarded by mu_
  bool quit_ = false;                    // guarded by mu_
  MapStore store_;                       // writer thread only (after construction)
  std::thread thread_;                   // last: started when everything above exists
};

}  // namespace irslam

#endif  // IRSLAM_DAEMON_MAP_WRITER_H_
