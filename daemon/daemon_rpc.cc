// The control API's methods (contracts.md §6) and the access each needs.
#include <cstdio>

#include "daemon/irslamd.h"

namespace irslam {
namespace {

// The start's log line: which map the mission goes on in (RobotCore::Start).
const char* StartLogText(robot::RobotCore::StartKind kind) {
  switch (kind) {
    case robot::RobotCore::StartKind::kLiveMap: return "on in the live map";
    case robot::RobotCore::StartKind::kSavedMap: return "relocalising in the saved map";
    case robot::RobotCore::StartKind::kResumed: return "resumed after the stop was released";
    case robot::RobotCore::StartKind::kNewMap:
    case robot::RobotCore::StartKind::kNone: break;
  }
  return "a new map";
}

}  // namespace

RpcMethodTable Daemon::MakeMethods() {
  // Each handler returns the whole response; an API server with deferred replies
  // calls reply(handler(request)).
  return RpcMethodTable({
      {"status", Access::kRead, [this](const rpc::Request& r) { return rpc::MakeResult(r.id, StatusJson()); }},
      {"map", Access::kRead,
       [this](const rpc::Request& r) { return rpc::MakeResult(r.id, maps_.Serve([this] { return LiveMap(); })); }},
      {"subscribe", Access::kRead, nullptr},  // carried out by the API server
      {"start", Access::kControl, [this](const rpc::Request& r) { return Start(r); }},
      // contracts §7: start in mode clean.
      {"clean", Access::kControl,
       [this](const rpc::Request& r) {
         rpc::Request c = r;
         if (!c.params.is_object()) c.params = nlohmann::json::object();
         c.params["mode"] = "clean";
         return Start(c);
       }},
      // Carried out by Daemon::Handle: its reply waits for the map writer's outcome.
      {"stop", Access::kControl, nullptr},
  });
}

nlohmann::json Daemon::Start(const rpc::Request& req) {
  const double now = RobotNow();
  if (foreign_.Present(WallNow())) {
    return rpc::MakeError(req.id, rpc::kRejected, std::string("start rejected: ") + kForeignCommanderReason);
  }
  // contracts §7: optional {"mode": "explore"|"clean", "fresh": bool}. fresh:
  // forget the saved map (the next save replaces its file); without it a start
  // with a saved map relocalises in it first (issue 14).
  std::string mode = settings_.core.mission.mode;
  bool fresh = false;
  if (req.params.is_object()) {
    for (const auto& [k, v] : req.params.items()) {
      if (k == "mode") {
        if (!v.is_string() || (v != "explore" && v != "clean"))
          return rpc::MakeError(req.id, rpc::kInvalidParams, "mode must be \"explore\" or \"clean\"");
        mode = v.get<std::string>();
      } else if (k == "fresh") {
        if (!v.is_boolean()) return rpc::MakeError(req.id, rpc::kInvalidParams, "fresh must be true or false");
        fresh = v.get<bool>();
      } else {
        return rpc::MakeError(req.id, rpc::kInvalidParams, "unknown parameter: " + k);
      }
    }
  } else if (!req.params.is_null() && !(req.params.is_array() && req.params.empty())) {
    return rpc::MakeError(req.id, rpc::kInvalidParams, "params must be an object");
  }
  ApplyPendingOptions();  // (normally done already when the mission ended)
  const bool running = core_->state() != control::MissionState::kIdle && core_->state() != control::MissionState::kDone &&
                       core_->state() != control::MissionState::kFault;
  if (!running) core_->SetCleanMode(mode == "clean");
  // fresh: the core forgets the saved map and its own live map (RobotCore::SetSavedMap).
  const bool forget = fresh && !running;
  if (forget) core_->SetSavedMap(std::nullopt);
  std::string why;
  if (!core_->Start(now, &why)) {
    if (forget) GiveSavedMap();  // not started: nothing forgotten
    return rpc::MakeError(req.id, rpc::kRejected, "start rejected: " + why);
  }
  if (forget && saved_map_) {
    saved_map_.reset();
    std::fprintf(stderr, "<6>irslamd: start fresh: the saved map is forgotten (its file is replaced at the next save)\n");
  }
  maps_.OnMissionStarted();
  // For irslam-replay (docs/replay.md): the mode goes with the start.
  if (recorder_) recorder_->Note(core_->clean_mode() ? "start_clean" : "start", now);
  std::fprintf(stderr, "<6>irslamd: mission started (mode %s, %s)\n", mode.c_str(),
               StartLogText(core_->last_start()));
  return rpc::MakeResult(req.id, {{"state", control::ToString(core_->state())}});
}

void Daemon::Stop(const rpc::Request& req, Reply reply) {
  const double now = RobotNow();
  core_->Stop(now);
  if (recorder_) recorder_->Note("stop", now);
  SendFrame(core_->StopFrame(), now);  // at once, not at the next period
  ApplyOutputs(now);
  const SaveResult saved = maps_.Save("stop", [this] { return LiveMap(); });
  if (saved == SaveResult::kQueued) {
    // Being written on the writer thread: the reply tells its outcome when it comes
    // (OnMapWritten); the control loop goes on meanwhile.
    stop_waiters_.push_back({req.id, std::move(reply)});
    return;
  }
  reply(StopReply(req.id, saved));
}

nlohmann::json Daemon::StopReply(const nlohmann::json& id, SaveResult saved) {
  std::fprintf(stderr, "<6>irslamd: stopped by request (map: %s)\n", ToString(saved));
  if (saved == SaveResult::kFailed) {
    // The wheels are stopped; the caller must not believe the map is safe.
    return rpc::MakeError(id, rpc::kMapNotSaved, "stopped, but the map was not saved: " + maps_.error());
  }
  return rpc::MakeResult(id, {{"state", control::ToString(core_->state())}, {"map", ToString(saved)}});
}

void Daemon::OnMapWritten(SaveResult result) {
  auto waiters = std::move(stop_waiters_);
  stop_waiters_.clear();
  for (auto& w : waiters) w.reply(StopReply(w.id, result));
}

}  // namespace irslam
