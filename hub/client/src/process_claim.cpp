// Claims one process holds at a time (see process_claim.hpp).
#include "afhub/hub/process_claim.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "afhub/hub/hub_files.hpp"

namespace afhub {

std::string claims_directory(const std::string& hub_directory, gid_t gid) {
  const std::string directory = hub_directory + "/claims";
  mkdir(directory.c_str(), 0755);
  struct stat info {};
  // Sticky: a member may not remove another's claim file. Only a directory of this user.
  if (gid != static_cast<gid_t>(-1) && lstat(directory.c_str(), &info) == 0 &&
      S_ISDIR(info.st_mode) && info.st_uid == geteuid() &&
      (chown(directory.c_str(), static_cast<uid_t>(-1), gid) != 0 ||
       chmod(directory.c_str(), 03770) != 0))
    std::fprintf(stderr, "afhub hub: cannot open %s to the hub's group: %s\n", directory.c_str(),
                 std::strerror(errno));
  return directory;
}

ProcessClaim::~ProcessClaim() {
  if (fd_ >= 0) close(fd_);  // the flock goes with the descriptor
}

bool ProcessClaim::take(const std::string& name, pid_t& holder) {
  holder = 0;
  const std::string directory = claims_directory(hub_directory());
  struct stat info {};
  if (lstat(directory.c_str(), &info) != 0 || !S_ISDIR(info.st_mode)) {
    unavailable_ = directory + ": not a directory (a symlink planted there?)";
    return true;
  }
  const std::string path = directory + "/" + name;
  // Read-only is enough for a flock, and lets a member of the hub's group use a file
  // another made. Never a symlink, nor a FIFO planted to block the open. O_CLOEXEC: a
  // process that re-executes itself takes it again.
  const int fd = open(path.c_str(), O_RDONLY | O_CREAT | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC, 0644);
  if (fd < 0 || fstat(fd, &info) != 0 || !S_ISREG(info.st_mode)) {
    unavailable_ = path + ": " + (fd < 0 ? std::strerror(errno) : "not a regular file");
    if (fd >= 0) close(fd);
    return true;
  }
  if (flock(fd, LOCK_EX | LOCK_NB) == 0) {
    if (fd_ >= 0) close(fd_);
    fd_ = fd;
    return true;
  }
  close(fd);
  holder = flock_holder(path).value_or(0);
  return false;
}

}  // namespace afhub
