// Socket and shared-memory access checks (see hub_access.hpp).
#include "hub_access.hpp"

#include <grp.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <optional>
#include <string>

#include "afhub/hub/hub_files.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/shm_layout/error.hpp"
#include "roudi_socket.hpp"

namespace afhub {
namespace {

std::string group_name(gid_t gid) {
  if (const group* entry = getgrgid(gid)) return entry->gr_name;
  return "gid " + std::to_string(gid);
}

}  // namespace

void require_hub_access() {
  const std::optional<HubIdentity> hub = running_hub();
  struct stat socket_info {};
  const bool socket = lstat(kRoudiSocketPath, &socket_info) == 0 && S_ISSOCK(socket_info.st_mode);
  struct stat identity {};
  if (!hub || hub->instance == 0 ||
      stat(hub_identity_path(hub_directory()).c_str(), &identity) != 0)
    throw Error(std::string("something answers at ") + kRoudiSocketPath +
                " but no afhub hub holds its lock in " + hub_directory() +
                ": a plain iceoryx RouDi (iox-roudi), or a socket left or planted there" +
                (socket ? " (it belongs to uid " + std::to_string(socket_info.st_uid) + ")" : "") +
                ". Stop it or remove it (as its owner or root), then start `afhub hub`.");
  if (!socket || socket_info.st_uid != identity.st_uid)
    throw Error(std::string(kRoudiSocketPath) + " belongs to uid " +
                std::to_string(socket_info.st_uid) + ", not to the hub's user (uid " +
                std::to_string(identity.st_uid) +
                "): another user planted it. Remove it as root, and restart the hub.");
  // iceoryx would wait forever on a socket it may not write to.
  for (const char* path : {kManagementSegment, kRoudiSocketPath}) {
    struct stat info {};
    if (access(path, R_OK | W_OK) != 0 && errno == EACCES && stat(path, &info) == 0)
      throw Error("permission denied on " + std::string(path) + ": the hub (uid " +
                  std::to_string(info.st_uid) + ") lets only the group '" +
                  group_name(info.st_gid) + "' use it. Join that group (`sudo usermod -aG " +
                  group_name(info.st_gid) +
                  " $USER`, then log in again), or have the hub started with `afhub hub --group "
                  "GROUP` for a group of yours.");
  }
}

}  // namespace afhub
