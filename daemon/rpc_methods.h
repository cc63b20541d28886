// The control API's method table: one entry per method, with the access it needs
// (daemon/access.h) written beside it, and its handler (a function from the
// request to the whole JSON-RPC response). Lookup, the access check and the log
// line of a denied call live here, once.
#ifndef IRSLAM_DAEMON_RPC_METHODS_H_
#define IRSLAM_DAEMON_RPC_METHODS_H_

#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "daemon/access.h"
#include "daemon/api_server.h"
#include "daemon/jsonrpc.h"

namespace irslam {

namespace rpc {
// `stop` stopped the wheels but the map could not be saved (message: why).
inline constexpr int kMapNotSaved = -32002;
}  // namespace rpc

struct RpcMethod {
  std::string name;
  Access access;
  // Returns the response (rpc::MakeResult or rpc::MakeError). Empty for methods the
  // API server carries out itself (subscribe): the table holds their access rule.
  std::function<nlohmann::json(const rpc::Request&)> handler;
};

class RpcMethodTable {
 public:
  explicit RpcMethodTable(std::vector<RpcMethod> methods) : methods_(std::move(methods)) {}

  const RpcMethod* Find(std::string_view name) const;
  // The access a method needs; an unknown method needs read access (so that a
  // stranger learns nothing, not even which names exist).
  Access Needs(std::string_view name) const;
  bool Allowed(const AccessPolicy& policy, const PeerCred& peer, Access need) const;
  // Access check, then the handler; a denied call is logged (the name escaped).
  nlohmann::json Handle(const rpc::Request& request, const PeerCred& peer, const AccessPolicy& policy) const;

  const std::vector<RpcMethod>& methods() const { return methods_; }

 private:
  std::vector<RpcMethod> methods_;
};

}  // namespace irslam

#endif  // IRSLAM_DAEMON_RPC_METHODS_H_
