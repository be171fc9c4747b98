// A claim that one process on this machine holds at a time (a device's teleoperation):
// a flock on a file in the hub's directory (claims/), which the kernel frees however
// its holder ends. A look at a channel's live writers leaves a window: two processes
// started at the same moment both passed one.
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
  // this process cannot see). True holding nothing when the claim cannot be taken (the
  // directory or the file not ours to use, or something else planted there):
  // unavailable() then says why.
  bool take(const std::string& name, pid_t& holder);
  const std::string& unavailable() const { return unavailable_; }

 private:
  int fd_ = -1;
  std::string unavailable_;
};

// The claims' directory of the hub in `hub_directory`, made if missing (0755, or for a
// hub's group `gid`, writable by its members: 03770).
std::string claims_directory(const std::string& hub_directory, gid_t gid = static_cast<gid_t>(-1));

}  // namespace afhub
