// A claim that one process on this machine holds at a time (a device's teleoperation):
// a flock on a file in the hub's directory, which the kernel frees however its holder
// ends. A look at a channel's live writers leaves a window: two processes started at
// the same moment both passed one.
#pragma once

#include <sys/types.h>

#include <string>

namespace afhub {

class ProcessClaim {
 public:
  ProcessClaim() = default;
  ~ProcessClaim();
  ProcessClaim(const ProcessClaim&) = delete;
  ProcessClaim& operator=(const ProcessClaim&) = delete;

  // Takes the claim `name` (a file name) for as long as this object lives. False when
  // another process holds it: `holder` is then its pid (0 when it is in a pid namespace
  // this process cannot see). Where the hub's directory cannot be written (a member of
  // another user's hub's group), true, holding nothing: the caller's look stands alone.
  bool take(const std::string& name, pid_t& holder);

 private:
  int fd_ = -1;
};

}  // namespace afhub
