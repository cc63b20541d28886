#include "daemon/map_writer.h"

#include <malloc.h>

#include <boost/asio/post.hpp>
#include <chrono>
#include <utility>

namespace irslam {

MapWriter::MapWriter(boost::asio::io_context& io, std::string dir, Done done)
    : io_(io), done_(std::move(done)), store_(std::move(dir)), thread_([this] { Loop(); }) {}

MapWriter::~MapWriter() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    quit_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

MapWriter::Outcome MapWriter::Process(MapStore& store, const Job& job) {
  // The shell's own clock: how long it took (reported, never decides anything).
  const auto t0 = std::chrono::steady_clock::now();
  auto m = std::make_shared<StoredMap>();
  m->seq = job.seq;
  m->reason = job.reason;
  m->map = job.encode();
  Outcome o;
  if (job.last && m->map == job.last->map) {
    o.result = Result::kUnchanged;
  } else if (!job.may_write) {
    o.result = Result::kNotWritten;
  } else {
    o.result = store.Save(*m, &o.error) ? Result::kSaved : Result::kFailed;
  }
  o.map = std::move(m);
  o.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return o;
}

void MapWriter::Submit(Job job) {
  busy_ = true;
  work_.emplace(io_.get_executor());
  {
    std::lock_guard<std::mutex> lock(mu_);
    job_.emplace(++next_id_, std::move(job));
  }
  cv_.notify_all();
}

std::optional<MapWriter::Outcome> MapWriter::Drain() {
  if (!busy_) return std::nullopt;
  std::unique_lock<std::mutex> lock(mu_);
  cv_.wait(lock, [this] { return !job_ && !writing_ && result_ && result_->first == next_id_; });
  Outcome outcome = std::move(result_->second);
  result_.reset();
  lock.unlock();
  drained_id_ = next_id_;
  busy_ = false;
  work_.reset();
  return outcome;
}

void MapWriter::Deliver(uint64_t id, Outcome outcome, std::shared_ptr<const StoredMap> last) {
  Garbage garbage{std::move(last), outcome.map};  // done_ keeps its own reference if it wants the map
  {
    // Delivered: Drain will not need it, and its map must not outlive done_'s use of it.
    std::lock_guard<std::mutex> lock(mu_);
    if (result_ && result_->first == id) result_.reset();
  }
  if (id != drained_id_) {  // else Drain delivered it already
    busy_ = false;
    work_.reset();
    done_(std::move(outcome));
  }
  Dispose(std::move(garbage));
}

void MapWriter::Dispose(Garbage garbage) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    for (auto& g : garbage) garbage_.push_back(std::move(g));
  }
  cv_.notify_all();
}

void MapWriter::Loop() {
  for (;;) {
    uint64_t id = 0;
    std::optional<Job> job;
    Garbage garbage;
    {
      std::unique_lock<std::mutex> lock(mu_);
      cv_.wait(lock, [this] { return job_.has_value() || !garbage_.empty() || quit_; });
      garbage.swap(garbage_);
      if (!job_ && quit_) return;  // quit, nothing left to write (the garbage goes with it)
      if (job_) {
        id = job_->first;
        job = std::move(job_->second);
        job_.reset();
        writing_ = true;
      }
    }
    garbage.clear();  // the maps the control thread no longer needs, freed here
    if (job) Run(id, std::move(*job));
    // The free pages back to the kernel: the encoding's strings, the freed
    // maps' blocks. One arena (daemon/main.cc), so this holds the lock the
    // control thread's allocations take while it walks the free lists
    // (0.05-0.17 ms for a fragmented 1.8-3 MB heap, measured on the loaded
    // 2-core host), like any of the encoding's thousands of allocations here.
    ::malloc_trim(0);
  }
}

void MapWriter::Run(uint64_t id, Job job) {
  Outcome outcome = Process(store_, job);
  std::shared_ptr<const StoredMap> last = std::move(job.last);  // freed on this thread too (Deliver)
  job = {};  // the snapshot goes here, not on the control thread
  {
    std::lock_guard<std::mutex> lock(mu_);
    writing_ = false;
    result_ = {id, outcome};
  }
  cv_.notify_all();
  boost::asio::post(io_, [this, alive = std::weak_ptr<int>(alive_), id, o = std::move(outcome),
                          last = std::move(last)]() mutable {
    if (alive.lock()) Deliver(id, std::move(o), std::move(last));
  });
}

}  // namespace irslam
