// Claims one process holds at a time (see process_claim.hpp).
#include "afhub/hub/process_claim.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>

#include "afhub/hub/hub_files.hpp"

namespace afhub {

ProcessClaim::~ProcessClaim() {
  if (fd_ >= 0) close(fd_);  // the flock goes with the descriptor
}

bool ProcessClaim::take(const std::string& name, pid_t& holder) {
  holder = 0;
  const std::string directory = hub_directory() + "/claims";
  if (mkdir(directory.c_str(), 0755) != 0 && errno != EEXIST) return true;
  const std::string path = directory + "/" + name;
  // O_CLOEXEC (open_own_file): a process that re-executes itself takes it again.
  const int fd = open_own_file(path, O_RDWR | O_CREAT, 0644);
  if (fd < 0) return true;
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
