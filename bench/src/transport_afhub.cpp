// afhub's own channels through the hub, two ways:
//   afhub: a queue of iceoryx samples, zero copy. The sender loans a chunk of the
//     payload's size and writes only the fields it needs into it, as a producer filling
//     its data in place would; the receiver reads it in place.
//   afhub-slot: a latest-value slot, as states and commands travel (see channel.hpp).
//     The sender updates its one chunk in place, writing the same fields; the receiver
//     copies the whole payload out and checks the copy.
#include <chrono>
#include <new>
#include <thread>

#include "afhub/hub/channel.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/shm_layout/bench_sample.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/health.hpp"
#include "afhub/shm_layout/slot_block.hpp"
#include "transport.hpp"

namespace afhub::bench {
namespace {

class AfhubTransport : public Transport {
 public:
  AfhubTransport(Side side, const std::string& session, PayloadKind kind)
      : slot_(is_slot_kind(kind)),
        writer_(channel(session, side == Side::kPing ? "ping" : "pong", kind), kind),
        reader_(channel(session, side == Side::kPing ? "pong" : "ping", kind), kind) {}

  // A slot writer's entry takes the largest payload before the handshake (a message of
  // round 0, which no exchange asks for): an entry outgrowing its size class moves to a
  // new block, which reaches the peer only once RouDi has connected that block's
  // publisher (its next discovery pass). Not what the bench measures.
  void connect(std::int64_t /*deadline_ns*/) override {
    if (slot_) send(kMaxPayloadBytes, 0, 0);
  }

  std::int64_t send(std::uint32_t bytes, std::uint64_t round,
                    std::int64_t peer_receive_ns) override {
    const std::int64_t send_ns = monotonic_ns();
    void* chunk = writer_.loan(bytes);
    if (!chunk)
      throw Error("afhub bench: shared memory exhausted for a " + std::to_string(bytes) +
                  " byte sample; see `afhub status` for the hub's pools");
    auto* sample = new (chunk) BenchSample{};
    sample->header.sim_step = round;
    sample->send_ns = send_ns;
    sample->peer_receive_ns = peer_receive_ns;
    touch_written(static_cast<char*>(chunk) + sizeof(BenchSample), bytes - sizeof(BenchSample),
                  round);
    writer_.publish(sample);
    return send_ns;
  }

  std::optional<Message> receive(std::int64_t deadline_ns) override {
    for (;;) {
      const auto* sample = static_cast<const BenchSample*>(reader_.latest());
      if (reader_.updated()) {
        Message message;
        message.bytes = static_cast<std::uint32_t>(reader_.latest_bytes());
        touch_read(reinterpret_cast<const char*>(sample) + sizeof(BenchSample),
                   message.bytes - sizeof(BenchSample), sample->header.sim_step, "afhub");
        message.receive_ns = monotonic_ns();
        message.round = sample->header.sim_step;
        message.send_ns = sample->send_ns;
        message.peer_receive_ns = sample->peer_receive_ns;
        return message;
      }
      if (monotonic_ns() > deadline_ns) return std::nullopt;
    }
  }

 private:
  static ChannelId channel(const std::string& session, const char* event, PayloadKind kind) {
    return {"afhub", "bench/" + session, std::string(event) + (is_slot_kind(kind) ? "_slot" : "")};
  }
  bool slot_;
  RawWriter writer_;
  RawLatestReader reader_;
};

// A production hub has no pools for samples this large; the hub the bench starts
// gets them (`afhub hub --bench-pools`, BenchHub). Refuses, saying what to do, a running hub
// without them.
void require_bench_pools() {
  LatestReader<Health> reader(
      {std::string(kService), std::string(kHubInstance), std::string(kHealthEvent)});
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(3);
  // The first health of a new hub may come before RouDi's mempool introspection.
  while ((!reader.latest() || reader.latest()->mempool_count == 0) &&
         std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  const Health* health = reader.latest();
  if (!health) throw Error("the hub publishes no health: is it an afhub hub?");
  // Free chunks of the pool iceoryx would take the largest sample's block of slots from
  // (the smallest that fits, in the payload segment; RouDi's own introspection segment
  // comes first), if that pool is sized for it: a production hub's next larger pool
  // holds catalogs, which the bench must not take. Two channels hold up to five chunks
  // each.
  constexpr std::uint32_t kNeeded = 16;
  const std::size_t block_bytes = slot_block_pool_bytes(first_slot_block_bytes(kMaxPayloadBytes));
  const MempoolUsage* fits = nullptr;
  for (std::uint32_t i = 0; i < health->mempool_count; ++i) {
    const MempoolUsage& pool = health->mempools[i];
    if (pool.segment_id != health->mempools[0].segment_id &&
        pool.chunk_payload_bytes >= block_bytes &&
        (!fits || pool.chunk_payload_bytes < fits->chunk_payload_bytes))
      fits = &pool;
  }
  const std::uint32_t free_chunks = fits && fits->chunk_payload_bytes <= block_bytes * 5 / 4
                                        ? fits->chunk_count - fits->used_chunks
                                        : 0;
  if (free_chunks < kNeeded)
    throw Error("the running hub has " + std::to_string(free_chunks) + " free chunks for " +
                std::to_string(kMaxPayloadBytes) + " byte samples; the bench needs " +
                std::to_string(kNeeded) +
                ". Stop it (`afhub hub stop`) and let the bench start one, or start it with "
                "`afhub hub --bench-pools`");
}

}  // namespace

std::unique_ptr<Transport> open_afhub_transport(Side side, const std::string& session, bool slot) {
  // The hub is the bench's own (BenchHub) or one that already ran.
  connect_to_hub(side == Side::kPing ? "bench" : "bench-peer", HubPolicy::kRequire);
  if (side == Side::kPing) require_bench_pools();
  return std::make_unique<AfhubTransport>(
      side, session, slot ? PayloadKind::kBenchSlot : PayloadKind::kBenchSample);
}

}  // namespace afhub::bench
