// Who may do what on the control socket (SO_PEERCRED of each client): root and
// the daemon's own user may do everything; otherwise `status`, `map` and
// `subscribe` need the read group (or the control group), `start` and `stop`
// the control group. An unset group means: whoever can open the socket (its
// 0660 mode and group already restrict that). Pure.
#ifndef IRSLAM_DAEMON_ACCESS_H_
#define IRSLAM_DAEMON_ACCESS_H_

#include <sys/types.h>

#include <optional>
#include <string>
#include <vector>

namespace irslam {

struct AccessPolicy {
  uid_t daemon_uid = 0;
  std::optional<gid_t> read_gid;
  std::optional<gid_t> control_gid;
};

enum class Access { kRead, kControl };

// groups: the peer's primary and supplementary groups, as the kernel gives them
// for the connection (SO_PEERGROUPS: PeerCred::groups in api_server.h).
bool Allowed(const AccessPolicy& policy, uid_t uid, const std::vector<gid_t>& groups, Access need);
// The groups /etc/group gives a user (primary gid plus its supplementary groups).
// Not for access checks: a process may hold groups its user is not listed in
// (setgroups, sg, systemd SupplementaryGroups=) and lose ones it is.
std::vector<gid_t> PeerGroups(uid_t uid, gid_t gid);
// Looks a group name up; nullopt (and *error) when it does not exist.
std::optional<gid_t> GroupId(const std::string& name, std::string* error);

}  // namespace irslam

#endif  // IRSLAM_DAEMON_ACCESS_H_
