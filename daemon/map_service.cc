#include "daemon/map_service.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <utility>

namespace irslam {
namespace {

size_t LineCount(const nlohmann::json& map) {
  return map.is_object() && map.contains("lines") && map["lines"].is_array() ? map["lines"].size() : 0;
}

}  // namespace

const char* ToString(SaveResult r) {
  switch (r) {
    case SaveResult::kSaved: return "saved";
    case SaveResult::kUnchanged: return "unchanged";
    case SaveResult::kNothing: return "nothing";
    case SaveResult::kDeferred: return "deferred";
    case SaveResult::kFailed: return "failed";
    case SaveResult::kQueued: return "queued";
  }
  return "?";
}

MapService::MapService(std::string state_dir, WallClock clock, double min_interval_s,
                       boost::asio::io_context* io)
    : store_(std::move(state_dir)), path_(store_.path()), clock_(std::move(clock)),
      min_interval_s_(min_interval_s) {
  if (io != nullptr) {
    writer_ = std::make_unique<MapWriter>(*io, store_.dir(), [this](MapWriter::Outcome o) { OnOutcome(o); });
  }
}

void MapService::Load() {
  if (auto loaded = store_.Load(&error_)) {
    stored_ = std::make_shared<const StoredMap>(std::move(*loaded));
  } else {
    stored_.reset();
  }
  if (!error_.empty()) std::fprintf(stderr, "<3>irslamd: %s\n", error_.c_str());
  if (stored_) {
    std::fprintf(stderr, "<6>irslamd: map loaded from %s (save %llu, %s, %zu lines)\n", path_.c_str(),
                 static_cast<unsigned long long>(stored_->seq), stored_->reason.c_str(), LineCount(stored_->map));
  }
}

std::string MapService::SetAside(const std::string& why) {
  stored_.reset();
  const std::string aside = path_ + ".bad";
  if (std::rename(path_.c_str(), aside.c_str()) != 0) {
    return "map: " + path_ + ": " + why + "; cannot move it aside: " + std::strerror(errno) + "; not used";
  }
  return "map: " + path_ + ": " + why + "; kept aside as " + aside + ", not used";
}

void MapService::OnCoreReplaced(MapEncoder old_map) {
  if (!live_ran_) return;  // the old core made no map: nothing to keep
  live_ran_ = false;
  held_ = std::move(old_map);
  Save("reload", [] { return MapEncoder([] { return nlohmann::json(); }); }, /*final=*/true);
}

nlohmann::json MapService::Serve(const MapSource& live) const {
  if (live_ran_) return live()();
  if (held_) return held_();
  if (stored_) {
    // Before any mission of this run: the map saved by the previous one.
    nlohmann::json m = stored_->map;
    m["saved"] = {{"seq", stored_->seq}, {"reason", stored_->reason}, {"path", path_}};
    return m;
  }
  return live()();
}

SaveResult MapService::Save(const char* reason, const MapSource& live, bool final) {
  return SaveImpl(reason, live, final, /*sync=*/!writer_);
}

SaveResult MapService::Flush(const char* reason, const MapSource& live) {
  next_.reset();  // the final save below covers it
  if (writer_) {
    if (auto o = writer_->Drain()) {
      const SaveResult r = Apply(*o);
      if (written_) written_(r);
    }
  }
  return SaveImpl(reason, live, /*final=*/true, /*sync=*/true);
}

SaveResult MapService::SaveImpl(const char* reason, const MapSource& live, bool final, bool sync) {
  if (!live_ran_ && !held_) return last_result_ = SaveResult::kNothing;  // nothing new
  // The snapshot only (no encoding here: that is the writer's).
  Request request{reason, live_ran_ ? live() : held_, final};
  if (!sync && writer_->busy()) {
    // Goes to the writer when the job in flight is done; its outcome is this save's.
    next_ = std::move(request);
    return SaveResult::kQueued;
  }
  return Submit(std::move(request), sync);
}

SaveResult MapService::Submit(Request request, bool sync) {
  MapWriter::Job job;
  job.seq = (stored_ ? stored_->seq : 0) + 1;
  job.reason = std::move(request.reason);
  job.encode = std::move(request.map);
  job.last = stored_;
  submitted_s_ = Now();
  job.may_write = request.final || submitted_s_ - last_write_s_ >= min_interval_s_;
  if (!sync) {
    // Handed over immutable; the control loop goes on at once.
    writer_->Submit(std::move(job));
    return last_result_ = SaveResult::kQueued;
  }
  return Apply(MapWriter::Process(store_, job));
}

void MapService::Poll(const MapSource& live) {
  if (!pending_reason_ || writing() || Now() - last_write_s_ < min_interval_s_) return;
  const std::string reason = *pending_reason_;
  pending_reason_.reset();
  Save(reason.c_str(), live);
}

void MapService::OnOutcome(const MapWriter::Outcome& o) {
  const SaveResult r = Apply(o);
  if (next_) {
    // A newer save was asked for meanwhile: its outcome answers (written_) instead.
    Request request = std::move(*next_);
    next_.reset();
    Submit(std::move(request), /*sync=*/false);
    return;
  }
  if (written_) written_(r);
}

SaveResult MapService::Apply(const MapWriter::Outcome& o) {
  using R = MapWriter::Result;
  last_save_ms_ = o.ms;
  switch (o.result) {
    case R::kUnchanged:
      ++unchanged_;
      pending_reason_.reset();
      return last_result_ = SaveResult::kUnchanged;
    case R::kNotWritten:
      // Changed, but the last write was too recent: Poll does it when its time comes.
      ++deferred_;
      pending_reason_ = o.map->reason;
      return last_result_ = SaveResult::kDeferred;
    case R::kSaved:
      last_write_s_ = submitted_s_;
      pending_reason_.reset();
      ++saves_;
      stored_ = o.map;
      error_.clear();
      return last_result_ = SaveResult::kSaved;
    case R::kFailed:
      break;
  }
  last_write_s_ = submitted_s_;
  pending_reason_.reset();
  ++save_errors_;
  error_ = o.error;
  std::fprintf(stderr, "<3>irslamd: %s\n", o.error.c_str());
  return last_result_ = SaveResult::kFailed;
}

nlohmann::json MapService::StatusJson() const {
  return {{"path", path_},
          {"seq", stored_ ? stored_->seq : 0},
          {"saved_map", stored_ != nullptr},
          {"saves", saves_},
          {"save_errors", save_errors_},
          {"unchanged", unchanged_},
          {"deferred", deferred_},
          {"pending", save_pending()},
          {"writing", writing()},
          {"last_result", ToString(last_result_)},
          {"last_save_ms", last_save_ms_},
          {"error", error_}};
}

}  // namespace irslam
