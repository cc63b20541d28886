// The control API's methods (contracts.md §6) and the access each needs.
#include <cstdio>

#include "daemon/irslamd.h"

namespace irslam {

RpcMethodTable Daemon::MakeMethods() {
  // Each handler returns the whole response; an API server with deferred replies
  // calls reply(handler(request)).
  return RpcMethodTable({
      {"status", Access::kRead, [this](const rpc::Request& r) { return rpc::MakeResult(r.id, StatusJson()); }},
      {"map", Access::kRead,
       [this](const rpc::Request& r) { return rpc::MakeResult(r.id, maps_.Serve([this] { return LiveMap(); })); }},
      {"subscribe", Access::kRead, nullptr},  // carried out by the API server
      {"start", Access::kControl, [this](const rpc::Request& r) { return Start(r); }},
      // Carried out by Daemon::Handle: its reply waits for the map writer's outcome.
      {"stop", Access::kControl, nullptr},
  });
}

nlohmann::json Daemon::Start(const rpc::Request& req) {
  const double now = RobotNow();
  if (foreign_.Present(WallNow())) {
    return rpc::MakeError(req.id, rpc::kRejected, std::string("start rejected: ") + kForeignCommanderReason);
  }
  ApplyPendingOptions();  // (normally done already when the mission ended)
  std::string why;
  if (!core_->Start(now, &why)) return rpc::MakeError(req.id, rpc::kRejected, "start rejected: " + why);
  maps_.OnMissionStarted();
  std::fprintf(stderr, "<6>irslamd: mission started\n");
  return rpc::MakeResult(req.id, {{"state", control::ToString(core_->state())}});
}

void Daemon::Stop(const rpc::Request& req, Reply reply) {
  const double now = RobotNow();
  core_->Stop(now);
  bus_->Send(core_->StopFrame());  // at once, not at the next period
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
