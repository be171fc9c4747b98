// Shared-memory pools of the hub, sized from the payload types rather than
// iceoryx's 206 MiB default. (RouDi keeps its introspection samples in a segment
// of its own, so these pools hold afhub payloads only.)
#include <algorithm>

#include "afhub/hub/hub_daemon.hpp"
#include "afhub/shm_layout/body_command.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/catalog.hpp"
#include "afhub/shm_layout/health.hpp"
#include "afhub/shm_layout/loop_stats.hpp"
#include "afhub/shm_layout/world.hpp"

namespace afhub {
namespace {

constexpr std::uint32_t round_up8(std::size_t bytes) {
  return static_cast<std::uint32_t>((bytes + 7) / 8 * 8);
}

}  // namespace

std::vector<MempoolSpec> hub_mempools() {
  // Chunk counts: each active body holds up to eight state and eight command chunks
  // (publisher history, a loan, and per reader a queued, a held and a retired
  // sample, for the hub's rate probe and a controller or two), for up to kMaxBodies
  // bodies with a margin.
  std::vector<MempoolSpec> pools = {
      {128, 512, "world commands, small iceoryx samples"},
      {round_up8(sizeof(BodyCommand)), 3072, "body commands"},
      {round_up8(sizeof(WorldState)), 64, "world state"},
      {round_up8(sizeof(BodyState)), 3072, "body states"},
      {round_up8(sizeof(Health)), 128, "hub health"},
      {round_up8(sizeof(LoopStats)), 256, "loop stats"},
      {round_up8(body_list_bytes(7)), 128, "catalogs and directories of up to 7 bodies"},
      {round_up8(body_list_bytes(60)), 32, "catalogs and directories of up to 60 bodies"},
      {round_up8(sizeof(BodyList)), 12, "catalogs and directories of up to kMaxBodies bodies"},
      // `afhub bench`: a ping and a pong channel per payload size, each holding up to
      // five chunks (a loan, the history, a queued, a held and a retired sample).
      {1 << 10, 16, "bench samples of 1 KiB"},
      {1 << 14, 16, "bench samples of 16 KiB"},
      {1 << 18, 16, "bench samples of 256 KiB"},
      {1 << 20, 16, "bench samples of 1 MiB"},
  };
  std::sort(pools.begin(), pools.end(), [](const MempoolSpec& a, const MempoolSpec& b) {
    return a.payload_bytes < b.payload_bytes;
  });
  return pools;
}

}  // namespace afhub
