#include "daemon/rpc_methods.h"

#include <cstdio>

namespace irslam {
const RpcMethod* RpcMethodTable::Find(std::string_view name) const {
  for (const auto& m : methods_) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

Access RpcMethodTable::Needs(std::string_view name) const {
  const RpcMethod* m = Find(name);
  return m ? m->access : Access::kRead;
}

bool RpcMethodTable::Allowed(const AccessPolicy& policy, const PeerCred& peer, Access need) const {
  return irslam::Allowed(policy, peer.uid, peer.groups, need);
}

nlohmann::json RpcMethodTable::Handle(const rpc::Request& req, const PeerCred& peer,
                                      const AccessPolicy& policy) const {
  const Access need = Needs(req.method);
  const bool control = need == Access::kControl;
  if (!Allowed(policy, peer, need)) {
    // Escaped: a name with a newline and "<0>" must not forge log lines.
    std::fprintf(stderr, "<4>api: denied method=%s uid=%u pid=%d\n", rpc::EscapeForLog(req.method).c_str(),
                 static_cast<unsigned>(peer.uid), static_cast<int>(peer.pid));
    return rpc::MakeError(req.id, rpc::kAccessDenied,
                          "access denied: " + req.method + " needs the " + (control ? "control" : "read") + " group");
  }
  const RpcMethod* m = Find(req.method);
  if (m == nullptr || !m->handler) {
    return rpc::MakeError(req.id, rpc::kMethodNotFound, "method not found: " + req.method);
  }
  return m->handler(req);
}

}  // namespace irslam
