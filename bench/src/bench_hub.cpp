// The hub `afhub bench` starts and stops (see bench.hpp).
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "afhub/bench/bench.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/rt/process_spawn.hpp"
#include "afhub/shm_layout/error.hpp"
#include "child_process.hpp"

namespace afhub::bench {
namespace {

std::string hub_log_path() {
  return "/tmp/afhub-bench-" + std::to_string(getpid()) + "-hub.log";
}

ChildProcess* g_hub = nullptr;  // never destroyed: stopped at exit

// At exit, after the iceoryx runtime's destructor (made later, so run earlier): stopped
// before it, the hub would leave the runtime's goodbye unanswered, and iceoryx says so.
void stop_bench_hub() {
  std::error_code ignored;
  if (g_hub->stop() == 0) std::filesystem::remove(hub_log_path(), ignored);
}

}  // namespace

void start_bench_hub_if_none() {
  if (probe_roudi() == RoudiPresence::kRunning) return;
  g_hub = new ChildProcess({this_executable(), "hub", "--bench-pools"}, hub_log_path());
  std::atexit(stop_bench_hub);
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (probe_roudi() != RoudiPresence::kRunning || !running_hub()) {
    if (!g_hub->running() || std::chrono::steady_clock::now() > give_up) {
      std::ostringstream log;
      log << std::ifstream(hub_log_path()).rdbuf();
      throw Error("the bench's hub (`afhub hub --bench-pools`) did not come up within 10 s; " +
                  hub_log_path() + " says:\n" + log.str());
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::fprintf(stderr,
               "afhub bench: no hub was running; started one with the bench's pools, stopped "
               "when the bench ends\n");
}

}  // namespace afhub::bench
