#include "daemon/access.h"

#include <grp.h>
#include <pwd.h>
#include <unistd.h>

#include <algorithm>

namespace irslam {

bool Allowed(const AccessPolicy& policy, uid_t uid, const std::vector<gid_t>& groups, Access need) {
  if (uid == 0 || uid == policy.daemon_uid) return true;
  const auto member = [&](const std::optional<gid_t>& g) {
    return g && std::find(groups.begin(), groups.end(), *g) != groups.end();
  };
  if (need == Access::kControl) return !policy.control_gid || member(policy.control_gid);
  // Reading: the read group, or the control group (control implies read).
  if (!policy.read_gid) return true;
  return member(policy.read_gid) || member(policy.control_gid);
}

std::vector<gid_t> PeerGroups(uid_t uid, gid_t gid) {
  std::vector<gid_t> groups = {gid};
  passwd pw{};
  passwd* found = nullptr;
  std::vector<char> buf(16384);
  if (::getpwuid_r(uid, &pw, buf.data(), buf.size(), &found) != 0 || found == nullptr) return groups;
  int n = 64;
  std::vector<gid_t> list(static_cast<size_t>(n));
  if (::getgrouplist(pw.pw_name, gid, list.data(), &n) < 0) {
    list.resize(static_cast<size_t>(n));
    if (::getgrouplist(pw.pw_name, gid, list.data(), &n) < 0) return groups;
  }
  list.resize(static_cast<size_t>(n));
  for (gid_t g : list) {
    if (std::find(groups.begin(), groups.end(), g) == groups.end()) groups.push_back(g);
  }
  return groups;
}

std::optional<gid_t> GroupId(const std::string& name, std::string* error) {
  group gr{};
  group* found = nullptr;
  std::vector<char> buf(16384);
  if (::getgrnam_r(name.c_str(), &gr, buf.data(), buf.size(), &found) != 0 || found == nullptr) {
    *error = "api: no such group '" + name + "'";
    return std::nullopt;
  }
  return gr.gr_gid;
}

}  // namespace irslam
