#include "daemon/map_service.h"

#include <cstdio>
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
  }
  return "?";
}

MapService::MapService(std::string state_dir, WallClock clock, double min_interval_s)
    : store_(std::move(state_dir)), path_(store_.path()), clock_(std::move(clock)),
      min_interval_s_(min_interval_s) {}

void MapService::Load() {
  stored_ = store_.Load(&error_);
  if (!error_.empty()) std::fprintf(stderr, "<3>irslamd: %s\n", error_.c_str());
  if (stored_) {
    std::fprintf(stderr, "<6>irslamd: map loaded from %s (save %llu, %s, %zu lines)\n", path_.c_str(),
                 static_cast<unsigned long long>(stored_->seq), stored_->reason.c_str(), LineCount(stored_->map));
  }
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
  if (!live_ran_ && !held_) return last_result_ = SaveResult::kNothing;  // nothing new
  nlohmann::json map = live_ran_ ? live() : *held_;
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
  return Write(reason, std::move(map));
}

void MapService::Poll(const MapSource& live) {
  if (!pending_reason_ || Now() - last_write_s_ < min_interval_s_) return;
  const std::string reason = *pending_reason_;
  pending_reason_.reset();
  Save(reason.c_str(), live);
}

SaveResult MapService::Write(const char* reason, nlohmann::json map) {
  pending_reason_.reset();
  StoredMap m;
  m.seq = (stored_ ? stored_->seq : 0) + 1;
  m.reason = reason;
  m.map = std::move(map);
  const WallTime t0 = clock_();
  last_write_s_ = SecondsBetween(WallTime{}, t0);
  std::string error;
  const bool ok = store_.Save(m, &error);
  last_save_ms_ = SecondsBetween(t0, clock_()) * 1e3;
  if (ok) {
    ++saves_;
    stored_ = std::move(m);
    error_.clear();
    return last_result_ = SaveResult::kSaved;
  }
  ++save_errors_;
  error_ = error;
  std::fprintf(stderr, "<3>irslamd: %s\n", error.c_str());
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
          {"last_result", ToString(last_result_)},
          {"last_save_ms", last_save_ms_},
          {"error", error_}};
}

}  // namespace irslam
