#include "daemon/map_writer.h"

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

void MapWriter::Deliver(uint64_t id, Outcome outcome) {
  if (id == drained_id_) return;  // Drain delivered it already
  busy_ = false;
  work_.reset();
  done_(std::move(outcome));
}

void MapWriter::Loop() {
  for (;;) {
    uint64_t id = 0;
    Job job;
    {
      std::unique_lock<std::mutex> lock(mu_);
      cv_.wait(lock, [this] { return job_.has_value() || quit_; });
      if (!job_) return;  // quit, nothing left to write
      id = job_->first;
      job = std::move(job_->second);
      job_.reset();
      writing_ = true;
    }
    Outcome outcome = Process(store_, job);
    job = {};  // the snapshot goes here, not on the control thread
    {
      std::lock_guard<std::mutex> lock(mu_);
      writing_ = false;
      result_ = {id, outcome};
    }
    cv_.notify_all();
    boost::asio::post(io_, [this, alive = std::weak_ptr<int>(alive_), id, o = std::move(outcome)]() mutable {
      if (alive.lock()) Deliver(id, std::move(o));
    });
  }
}

}  // namespace irslam
