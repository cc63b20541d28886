// The map service: owns the saved map (daemon/map_store.h) and decides what the
// `map` method serves and what gets saved, and when.
//
// Serves: the live core's map once a mission ran on it; else the map kept from a
// core that a reload replaced; else the map saved by the previous run (with a
// "saved" member); else the (empty) live map.
//
// Saves (reason "model", "stop", "shutdown", "reload") write the same candidate,
// and never:
//   - when nothing ran (no mission since start, or since a reload replaced the
//     core and its map was kept): the saved map stays as it is; a reload never
//     makes an empty map the one served or saved;
//   - a map identical to the last one saved ("unchanged": a `stop` storm writes
//     the SD card once);
//   - more often than once per min_interval_s, except the final save at shutdown:
//     a save asked for sooner is "deferred" and done by Poll() when its time comes.
// A save that fails is reported (Save's result, status.map_store.error, the log).
//
// With an io_context (the daemon), the map is encoded, compared and written by
// a MapWriter thread (daemon/map_writer.h): Save takes the typed snapshot (the
// source's MapEncoder), hands it over and returns kQueued at once; the outcome
// (kSaved, kUnchanged, kDeferred: changed but too soon, kFailed) arrives later on
// the io_context, updates the status and is passed to the written() callback
// (the daemon answers a `stop` waiting for it). A save asked for while one is in
// flight waits (the newest only) and goes to the writer when that one's outcome
// is in; the callback then waits for its outcome too. Without an io_context
// (tests, tools) Save does the same synchronously. The final save at shutdown
// (Flush) always encodes and writes synchronously, after the job in flight.
#ifndef IRSLAM_DAEMON_MAP_SERVICE_H_
#define IRSLAM_DAEMON_MAP_SERVICE_H_

#include <boost/asio/io_context.hpp>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "daemon/map_store.h"
#include "daemon/map_writer.h"
#include "daemon/wall_clock.h"

namespace irslam {

// kQueued: handed to the writer thread; the outcome (kSaved, kUnchanged, kDeferred
// or kFailed) comes later.
enum class SaveResult { kSaved, kUnchanged, kNothing, kDeferred, kFailed, kQueued };
const char* ToString(SaveResult r);

class MapService {
 public:
  // The live core's map: a snapshot taken now (control thread), encoded later.
  using MapSource = std::function<MapEncoder()>;
  static constexpr double kDefaultMinIntervalS = 5.0;

  // The outcome of a queued save (kSaved, kUnchanged, kDeferred or kFailed), on the io_context.
  using Written = std::function<void(SaveResult)>;

  // io: write on a MapWriter thread and deliver outcomes there; nullptr: write synchronously.
  MapService(std::string state_dir, WallClock clock, double min_interval_s = kDefaultMinIntervalS,
             boost::asio::io_context* io = nullptr);
  void set_written(Written w) { written_ = std::move(w); }

  // At start: reads the previous run's map (a bad file is moved aside and logged).
  void Load();
  // The loaded map turned out unusable (it checks out as a file, but its
  // content does not make a map: daemon/core_json.h MapFromJson): the file is
  // moved aside as map.json.bad (replacing an older one) and forgotten, as if
  // there had been none. Returns a one-line account for the log.
  std::string SetAside(const std::string& why);
  // A mission started on the live core: from now on its map is the one to serve and save.
  void OnMissionStarted() { live_ran_ = true; }
  // The core is about to be replaced (a reload): its map, if a mission made one, is
  // saved now if it was not yet (ignoring the rate limit) and served until a
  // mission starts on the new core.
  void OnCoreReplaced(MapEncoder old_map);

  nlohmann::json Serve(const MapSource& live) const;
  // final: not rate-limited (reload, shutdown).
  SaveResult Save(const char* reason, const MapSource& live, bool final = false);
  // The save at shutdown: waits for the write in flight, then writes synchronously.
  SaveResult Flush(const char* reason, const MapSource& live);
  // Once per control period: a deferred save whose time has come is done now.
  void Poll(const MapSource& live);

  bool has_live_map() const { return live_ran_; }
  bool save_pending() const { return pending_reason_.has_value() || next_.has_value(); }
  bool writing() const { return writer_ && writer_->busy(); }
  const std::string& error() const { return error_; }
  const std::shared_ptr<const StoredMap>& stored() const { return stored_; }
  const std::string& path() const { return path_; }
  nlohmann::json StatusJson() const;

 private:
  struct Request {
    std::string reason;
    MapEncoder map;
    bool final = false;
  };
  SaveResult SaveImpl(const char* reason, const MapSource& live, bool final, bool sync);
  // Hands the request to the writer (or does it here: sync).
  SaveResult Submit(Request request, bool sync);
  SaveResult Apply(const MapWriter::Outcome& outcome);  // a finished job's outcome
  void OnOutcome(const MapWriter::Outcome& outcome);     // from the writer, on the io_context
  double Now() const { return SecondsBetween(WallTime{}, clock_()); }

  MapStore store_;
  std::string path_;
  WallClock clock_;
  double min_interval_s_;
  std::shared_ptr<const StoredMap> stored_;  // the last map saved or loaded (the writer reads it too)
  MapEncoder held_;                    // kept from a replaced core
  bool live_ran_ = false;              // a mission ran on the live core
  std::optional<std::string> pending_reason_;  // a deferred save (too soon): Poll does it
  std::optional<Request> next_;        // asked for while a job is in flight
  double last_write_s_ = -1e18;
  double submitted_s_ = 0;             // when the job in flight (or the last) was handed over
  uint64_t saves_ = 0, save_errors_ = 0, unchanged_ = 0, deferred_ = 0;
  double last_save_ms_ = 0;
  SaveResult last_result_ = SaveResult::kNothing;
  std::string error_;
  Written written_;
  std::unique_ptr<MapWriter> writer_;  // last: its thread stops before the rest goes
};

}  // namespace irslam

#endif  // IRSLAM_DAEMON_MAP_SERVICE_H_
