#include "daemon/rpc_methods.h"

#include <cstdio>

namespace irslam {
namespace {

// A client's string for a log line: printable ASCII as it is, every other byte
// (newline, control characters, non-ASCII) and the backslash as \xNN, so that a
// name with a newline and "<0>" cannot forge log lines.
std::string LogField(std::string_view s) {
  std::string out;
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u < 0x7f && c != '\\') {
      out += c;
    } else {
      char buf[5];
      std::snprintf(buf, sizeof buf, "\\x%02x", u);
      out += buf;
    }
  }
  return out;
}

}  // namespace

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
  return irslam::Allowed(policy, peer.uid, PeerGroups(peer.uid, peer.gid), need);
}

nlohmann::json RpcMethodTable::Handle(const rpc::Request& req, const PeerCred& peer,
                                      const AccessPolicy& policy) const {
  const Access need = Needs(req.method);
  const bool control = need == Access::kControl;
  if (!Allowed(policy, peer, need)) {
    // Escaped: a name with a newline and "<0>" must not forge log lines.
    std::fprintf(stderr, "<4>api: denied method=%s uid=%u pid=%d\n", LogField(req.method).c_str(),
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
