// The hub daemon: RouDi in-process with mempools sized for afhub's payloads, the
// catalog of live bodies, and the system's health. Runs in the foreground until
// SIGINT or SIGTERM.
#pragma once

#include <cstdint>
#include <vector>

namespace afhub {

struct MempoolSpec {
  std::uint32_t payload_bytes;
  std::uint32_t chunk_count;
  const char* holds;  // which payloads the pool is for
};

// The hub's shared-memory pools, smallest first.
std::vector<MempoolSpec> hub_mempools();

// Runs the hub; returns the process exit code (0 on a clean stop).
int run_hub_daemon();

// Stops the running hub (SIGTERM, then waits up to 5 s); returns an exit code.
int stop_hub();

}  // namespace afhub
