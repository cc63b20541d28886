// ApiServer's way to the control loop and back. A parsed request is posted to
// the control thread, run by the Dispatcher there, and its answer posted back
// to the session on the API thread. `status`, `map` and notification payloads
// are built at most once per control period (NewPeriod()) however many clients
// ask, and each shared result is serialised once on the API thread.
#include <boost/asio/post.hpp>

#include "daemon/api_server.h"
#include "daemon/internal/api_session.h"

namespace irslam {

namespace asio = boost::asio;

void ApiServer::PostToControl(std::weak_ptr<Session> session,
                              std::shared_ptr<const rpc::Request> request, PeerCred peer) {
  asio::post(control_, [this, alive = std::weak_ptr<int>(alive_), session = std::move(session),
                        request = std::move(request), peer = std::move(peer)]() mutable {
    if (alive.expired()) return;
    OnControl(std::move(session), std::move(request), peer);
  });
}

void ApiServer::OnControl(std::weak_ptr<Session> session,
                          std::shared_ptr<const rpc::Request> req, const PeerCred& peer) {
  // The way back to the API thread; harmless when the client or the server is gone.
  auto deliver = [loop = std::weak_ptr<Loop>(loop_), session, req](Outcome o) {
    const auto l = loop.lock();
    if (!l) return;
    asio::post(l->io, [session, req, o = std::move(o)]() mutable {
      if (const auto s = session.lock()) s->OnAnswer(req, std::move(o));
    });
  };
  if (!req) {  // a status notification's payload, built once per period
    Cached& c = cache_["@notify"];
    if (c.result && c.period == period_) {
      ++counters_->coalesced;
    } else {
      c = {period_, std::make_shared<const nlohmann::json>(dispatcher_->StatusNotification())};
    }
    deliver(Outcome{nullptr, c.result, "@notify"});
    return;
  }
  if (req->method == "subscribe") {
    if (!dispatcher_->MaySubscribe(peer)) {
      deliver(Outcome{rpc::MakeError(req->id, rpc::kAccessDenied, "access denied: subscribe"), {}, {}});
    } else {
      const double rate = api_internal::SubscribeRate(req->params, limits_.max_rate_hz).value_or(1);
      deliver(Outcome{rpc::MakeResult(req->id, {{"subscribed", true}, {"rate", rate}}), {}, {}});
    }
    return;
  }
  const bool readable = req->method == "status" || req->method == "map";
  // Neither takes params (contracts.md §6): padded params must not get past the sharing.
  if (readable && dispatcher_->MaySubscribe(peer)) {
    const auto it = cache_.find(req->method);
    if (it != cache_.end() && it->second.result && it->second.period == period_) {
      ++counters_->coalesced;
      deliver(Outcome{nullptr, it->second.result, req->method});
      return;
    }
    dispatcher_->Handle(*req, peer,
                        [this, alive = std::weak_ptr<int>(alive_), deliver,
                         key = req->method](nlohmann::json response) {
                          if (alive.expired() || !response.contains("result")) {
                            deliver(Outcome{std::move(response), {}, {}});
                            return;
                          }
                          auto r = std::make_shared<const nlohmann::json>(
                              std::move(response["result"]));
                          cache_[key] = {period_, r};
                          deliver(Outcome{nullptr, std::move(r), key});
                        });
    return;
  }
  if (!readable) cache_.clear();  // a command may change what status and map say
  dispatcher_->Handle(*req, peer, [deliver](nlohmann::json response) {
    deliver(Outcome{std::move(response), {}, {}});
  });
}

const std::string& ApiServer::SharedText(const std::string& key,
                                         const std::shared_ptr<const nlohmann::json>& result) {
  auto& [held, text] = texts_[key];
  if (held != result) {
    held = result;
    text = key == "@notify" ? rpc::MessageText(rpc::MakeNotification("status", *result))
                            : rpc::MessageText(*result);
  }
  return text;
}

}  // namespace irslam
