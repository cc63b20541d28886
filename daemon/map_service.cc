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
    writer_ = std::make_unique<MapWriter>(*io, store_.dir(), [this](MapWriter::Outcome o) {
      const SaveResult r = Apply(o);
      if (written_) written_(r);
    });
  }
}

void MapService::Load() {
  stored_ = store_.Load(&error_);
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

void MapService::OnCoreReplaced(const nlohmann::json& old_map) {
  if (!live_ran_) return;  // the old core made no map: nothing to keep
  live_ran_ = false;
  held_ = old_map;
  Save("reload", [] { return nlohmann::json(); }, /*final=*/true);
}

nlohmann::json MapService::Serve(const MapSource& live) const {
  if (live_ran_) return live();
  if (held_) return *held_;
  if (stored_) {
    // Before any mission of this run: the map saved by the previous one.
    nlohmann::json m = stored_->map;
    m["saved"] = {{"seq", stored_->seq}, {"reason", stored_->reason}, {"path", path_}};
    return m;
  }
  return live();
}

SaveResult MapService::Save(const char* reason, const MapSource& live, bool final) {
  return SaveImpl(reason, live, final, /*sync=*/!writer_);
}

SaveResult MapService::Flush(const char* reason, const MapSource& live) {
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
  nlohmann::json map = live_ran_ ? live() : *held_;
  if (in_flight_) {
    // This very map is being written: its outcome is this save's.
    if (map == in_flight_->map) return SaveResult::kQueued;
    // A newer one: written when the writer is free (Poll).
    ++deferred_;
    pending_reason_ = reason;
    return last_result_ = SaveResult::kDeferred;
  }
  if (stored_ && map == stored_->map) {
    ++unchanged_;
    pending_reason_.reset();
    return last_result_ = SaveResult::kUnchanged;
  }
  if (!final && Now() - last_write_s_ < min_interval_s_) {
    ++deferred_;
    pending_reason_ = reason;
    return last_result_ = SaveResult::kDeferred;
  }
  return Write(reason, std::move(map), sync);
}

void MapService::Poll(const MapSource& live) {
  if (!pending_reason_ || writing() || Now() - last_write_s_ < min_interval_s_) return;
  const std::string reason = *pending_reason_;
  pending_reason_.reset();
  Save(reason.c_str(), live);
}

SaveResult MapService::Write(const char* reason, nlohmann::json map, bool sync) {
  pending_reason_.reset();
  auto m = std::make_shared<StoredMap>();
  m->seq = (stored_ ? stored_->seq : 0) + 1;
  m->reason = reason;
  m->map = std::move(map);
  const WallTime t0 = clock_();
  last_write_s_ = SecondsBetween(WallTime{}, t0);
  if (!sync && writer_) {
    // Handed over immutable; the control loop goes on at once.
    in_flight_ = std::move(m);
    writer_->Submit(in_flight_);
    return last_result_ = SaveResult::kQueued;
  }
  MapWriter::Outcome o;
  o.ok = store_.Save(*m, &o.error);
  o.ms = SecondsBetween(t0, clock_()) * 1e3;
  o.map = std::move(m);
  return Apply(o);
}

SaveResult MapService::Apply(const MapWriter::Outcome& o) {
  in_flight_.reset();
  last_save_ms_ = o.ms;
  if (o.ok) {
    ++saves_;
    stored_ = *o.map;
    error_.clear();
    return last_result_ = SaveResult::kSaved;
  }
  ++save_errors_;
  error_ = o.error;
  std::fprintf(stderr, "<3>irslamd: %s\n", o.error.c_str());
  return last_result_ = SaveResult::kFailed;
}

nlohmann::json MapService::StatusJson() const {
  return {{"path", path_},
          {"seq", stored_ ? stored_->seq : 0},
          {"saved_map", stored_.has_value()},
          {"saves", saves_},
          {"save_errors", save_errors_},
          {"unchanged", unchanged_},
          {"deferred", deferred_},
          {"pending", pending_reason_.has_value()},
          {"writing", in_flight_ != nullptr},
          {"last_result", ToString(last_result_)},
          {"last_save_ms", last_save_ms_},
          {"error", error_}};
}

}  // namespace irslam
