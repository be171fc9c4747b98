// The hub daemon: RouDi in-process with mempools sized for afhub's payloads, the
// catalog of live bodies, and the system's health. Runs in the foreground until
// SIGINT or SIGTERM.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace afhub {

struct MempoolSpec {
  std::uint32_t payload_bytes;
  std::uint32_t chunk_count;
  std::string holds;  // which payloads the pool is for
};

// The pools every hub has, sized from the payload types and their limits
// (shm_layout/limits.hpp), smallest first.
std::vector<MempoolSpec> default_mempools();

// `pools` with the chunks `afhub bench` needs on top (its ping and pong samples up to
// 1 MiB), added to the pools those samples fit: no pool is put below another's
// payloads.
std::vector<MempoolSpec> with_bench_pools(std::vector<MempoolSpec> pools);

// A pool file: one pool per line, "<payload bytes> <chunk count>", '#' starts a
// comment. Throws afhub::Error naming the file and line of a bad entry.
std::vector<MempoolSpec> read_mempool_file(const std::string& path);

// "<payload bytes>:<chunk count>", as `afhub hub --pool` takes it. Throws afhub::Error.
MempoolSpec parse_mempool(const std::string& text);

// `extra` added to `pools`: a pool of a size already there replaces its count.
// Sorted by size; throws afhub::Error when there are more than iceoryx allows.
std::vector<MempoolSpec> merge_mempools(std::vector<MempoolSpec> pools,
                                        const std::vector<MempoolSpec>& extra);

struct HubOptions {
  std::vector<MempoolSpec> mempools = default_mempools();
  // Who may use the hub's shared memory besides its user: the members of this group
  // (empty: the hub user's own group).
  std::string group;
};

// Runs the hub; returns the process exit code (0 on a clean stop).
int run_hub_daemon(const HubOptions& options);

// Stops the running hub (SIGTERM, then waits up to 5 s); returns an exit code.
// With processes attached, it lists them and stops the hub only when `force`.
int stop_hub(bool force);

}  // namespace afhub
