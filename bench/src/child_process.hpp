// The processes `afhub bench` starts: its peers, the physics, cyclictest and
// rosmaster. Each gets SIGTERM when the bench dies, and is stopped (SIGTERM, then
// SIGKILL) when its ChildProcess goes out of scope.
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace afhub::bench {

class ChildProcess {
 public:
  // Runs argv[0] (searched in PATH) with stdout and stderr to `output_path`; throws
  // afhub::Error when it cannot. A program that is not found exits with 127.
  explicit ChildProcess(const std::vector<std::string>& argv,
                        const std::string& output_path = "/dev/null");
  ~ChildProcess() { stop(); }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  // Waits up to timeout_ms for the exit; returns the exit code, 128 + signal when
  // killed, or -1 when still running.
  int wait(int timeout_ms);
  // SIGTERM, then SIGKILL after `grace_ms`; returns the exit code as wait() does.
  int stop(int grace_ms = 5000);
  bool running();

 private:
  pid_t pid_ = -1;
  int exit_code_ = -1;
};

// The first line of the file at `path` that holds `text` (what a child said), or "".
std::string first_line_with(const std::string& path, const std::string& text);

}  // namespace afhub::bench
