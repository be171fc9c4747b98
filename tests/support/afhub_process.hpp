// Runs the afhub executable from tests: to completion with a timeout, or in the
// background, and stops processes it started.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <csignal>
#include <string>
#include <vector>

#include "text_contains.hpp"

namespace afhub::test {

struct RunResult {
  int exit_code = -1;  // 128 + signal when killed; -1 when it timed out
  std::string out;
  std::string err;
  double seconds = 0.0;
};

// Runs `afhub args...` and waits at most `timeout` for it.
RunResult run_afhub(const std::vector<std::string>& args,
                    std::chrono::milliseconds timeout = std::chrono::seconds(20));
// Runs `argv` (argv[0] found on PATH) and waits at most `timeout` for it.
RunResult run_command(const std::vector<std::string>& argv,
                      std::chrono::milliseconds timeout = std::chrono::seconds(20));

// Starts `argv` (argv[0] found on PATH) in the background, its output shared with the test's.
pid_t spawn_command(const std::vector<std::string>& argv);
// Starts `afhub args...` in the background (stdout and stderr to `log_path`).
pid_t spawn_afhub(const std::vector<std::string>& args, const std::string& log_path = "/dev/null");
// The same, with `wrapper` before afhub, e.g. {"unshare", "--pid", "--fork"} (found on PATH).
pid_t spawn_wrapped_afhub(const std::vector<std::string>& wrapper,
                          const std::vector<std::string>& args,
                          const std::string& log_path = "/dev/null");

// How long a stop waits by default: an exit that unmaps a process's memory took over
// 5 s on a loaded machine (a recorder's, beside two busy loops and a build).
inline constexpr std::chrono::milliseconds kStopTimeout = std::chrono::seconds(15);

// Sends `signal`, waits up to `timeout` for the exit, SIGKILLs after that; returns
// the exit code (128 + signal when killed by one).
int stop_process(pid_t pid, int signal, std::chrono::milliseconds timeout = kStopTimeout);

// Stops (SIGTERM, then SIGKILL) every child of this process still running and
// describes each ("pid: command line"). A test binary calls it last: a client left
// running would attach to the next binary's hub and break its tests.
std::vector<std::string> stop_leftover_children();

// A process that is stopped (SIGTERM, then SIGKILL) when the test leaves its scope,
// however it leaves: a failed assertion never leaves a hub running.
struct ScopedProcess {
  ScopedProcess(pid_t started) : pid(started) {}
  ScopedProcess(const ScopedProcess&) = delete;
  ScopedProcess& operator=(const ScopedProcess&) = delete;
  ~ScopedProcess() { stop(); }
  // Stops it now with `signal` (0: waits for it to end by itself), as stop_process;
  // returns its exit code (0 when it was already stopped). Stopped once: its pid is
  // then forgotten, so the destructor never signals a pid the system gave another.
  int stop(int signal = SIGTERM, std::chrono::milliseconds timeout = kStopTimeout);
  pid_t pid;
};

// A child's exit code once it ended (128 + signal when killed by one), or -1 while it runs.
int exit_code_if_ended(pid_t pid);

// Waits up to `timeout` for the process to end by itself; returns its exit code,
// or -1 when it is still running (it is then left to the ScopedProcess).
int wait_for_exit(ScopedProcess& process, std::chrono::milliseconds timeout);

// Every thread's stack of each process named `pattern` (pgrep -f), through gdb: for a
// test to print when it finds a process hung, so that the cause can be read from CI's log.
std::string stack_traces(const std::string& pattern);

// Waits until `predicate` holds, polling every 10 ms, for at most `timeout`.
template <class Predicate>
bool wait_until(Predicate predicate, std::chrono::milliseconds timeout) {
  auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!predicate()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    struct timespec pause {
      0, 10'000'000
    };
    nanosleep(&pause, nullptr);
  }
  return true;
}

std::string afhub_executable();

// How many times `part` occurs in `text` (overlaps counted).
int occurrences(const std::string& text, const std::string& part);
// The comma-separated numbers that follow `key` in `text` (searched from `from`), up
// to the closing ']'. For text output only: JSON is read with parse_json (strict_json.hpp).
std::vector<double> numbers_after(const std::string& text, const std::string& key,
                                  std::size_t from = 0);
std::string read_file(const std::string& path);

}  // namespace afhub::test
