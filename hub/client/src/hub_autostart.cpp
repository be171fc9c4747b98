// Making sure a hub runs (ensure_hub, hub_presence.hpp): waiting for one, or starting
// `afhub hub` in the background, detached from this process.
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <thread>

#include "afhub/hub/hub_files.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/rt/process_spawn.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub_executable.hpp"

namespace afhub {
namespace {

// A hub writes about 150 MB of segments as it starts: under load (a build beside, tests
// in parallel) that took over 10 s once, and the started hub came up just after.
constexpr auto kAutostartTimeout = std::chrono::seconds(30);

// Starts `afhub hub` in a session of its own (no Ctrl-C from this terminal), its
// output in `log_path`; it outlives this process.
void start_background_hub(const std::string& exe, const std::vector<std::string>& options,
                          const std::string& log_path) {
  const int log = open_own_file(log_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (log < 0)
    throw Error("cannot start a hub: cannot write its log " + log_path + ": " +
                std::strerror(errno));
  std::vector<std::string> argv{exe, "hub"};
  argv.insert(argv.end(), options.begin(), options.end());
  SpawnOptions spawn;
  spawn.stdout_fd = spawn.stderr_fd = log;
  spawn.detached = true;
  try {
    spawn_process(argv, spawn);
  } catch (...) {
    close(log);
    throw;
  }
  close(log);
}

std::string hub_log_tail(const std::string& log_path) {
  std::ifstream in(log_path);
  std::string line, all;
  while (std::getline(in, line)) all += "  " + line + "\n";
  return all;
}

// With kRequire and a wait: probing the socket, never iceoryx, whose runtime would
// wait 60 s, then abort.
void wait_for_hub(std::chrono::milliseconds wait, const std::string& who) {
  char seconds[32];
  std::snprintf(seconds, sizeof seconds, "%g", static_cast<double>(wait.count()) * 1e-3);
  std::fprintf(stderr, "%s: no hub is running yet; waiting up to %s s for one\n", who.c_str(),
               seconds);
  const auto deadline = std::chrono::steady_clock::now() + wait;
  while (probe_roudi() != RoudiPresence::kRunning) {
    if (stop_requested()) throw Stopped("stopped while waiting for a hub");
    if (std::chrono::steady_clock::now() > deadline)
      throw Error("no hub came up within " + std::string(seconds) +
                  " s. Start one with `afhub hub` (foreground), or `afhub run MODEL`, which "
                  "starts one in the background; or wait longer (--wait)");
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

}  // namespace

void ensure_hub(HubPolicy policy, std::chrono::milliseconds wait, const std::string& who,
                const std::vector<std::string>& hub_options) {
  if (probe_roudi() == RoudiPresence::kRunning) return;
  if (policy == HubPolicy::kRequire && wait.count() > 0) return wait_for_hub(wait, who);
  if (policy == HubPolicy::kRequire)
    throw Error(
        "no hub is running. Start one with `afhub hub` (foreground) or let `afhub run` start one "
        "in the background.");
  const std::string exe = afhub_executable();
  const std::string log_path = hub_log_path(own_hub_directory());
  start_background_hub(exe, hub_options, log_path);
  const auto deadline = std::chrono::steady_clock::now() + kAutostartTimeout;
  while (probe_roudi() != RoudiPresence::kRunning) {
    if (std::chrono::steady_clock::now() > deadline)
      throw Error("started a hub (" + exe + " hub) but it did not come up within " +
                  std::to_string(kAutostartTimeout.count()) + " s; its log " + log_path +
                  " says:\n" + hub_log_tail(log_path));
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const std::optional<pid_t> pid = running_hub_pid();
  std::fprintf(stderr,
               "afhub: no hub was running; started one in the background (pid %d, log %s). "
               "Stop it with `afhub hub stop`.\n",
               pid ? static_cast<int>(*pid) : -1, log_path.c_str());
}

}  // namespace afhub
