// afhub's own channels: iceoryx through the hub, zero copy. The sender loans a
// chunk of the payload's size and writes only the fields it needs into it, as a
// producer filling its data in place would; the receiver reads it in place.
#include <new>

#include "afhub/hub/channel.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/shm_layout/bench_sample.hpp"
#include "afhub/shm_layout/error.hpp"
#include "transport.hpp"

namespace afhub::bench {
namespace {

class AfhubTransport : public Transport {
 public:
  AfhubTransport(Side side, const std::string& session)
      : writer_(channel(session, side == Side::kPing ? "ping" : "pong"), BenchSample::kKind),
        reader_(channel(session, side == Side::kPing ? "pong" : "ping"), BenchSample::kKind) {}

  std::int64_t send(std::uint32_t bytes, std::uint64_t round,
                    std::int64_t peer_receive_ns) override {
    void* chunk = writer_.loan(bytes);
    if (!chunk)
      throw Error("afhub bench: shared memory exhausted for a " + std::to_string(bytes) +
                  " byte sample; see `afhub status` for the hub's pools");
    auto* sample = new (chunk) BenchSample{};
    sample->round = round;
    sample->peer_receive_ns = peer_receive_ns;
    return writer_.publish(sample);
  }

  std::optional<Message> receive(std::int64_t deadline_ns) override {
    for (;;) {
      const auto* sample = static_cast<const BenchSample*>(reader_.latest());
      if (reader_.updated()) {
        Message message;
        message.receive_ns = monotonic_ns();
        message.bytes = static_cast<std::uint32_t>(reader_.latest_bytes());
        message.round = sample->round;
        message.send_ns = sample->header.publish_stamp_ns;
        message.peer_receive_ns = sample->peer_receive_ns;
        return message;
      }
      if (monotonic_ns() > deadline_ns) return std::nullopt;
    }
  }

 private:
  static ChannelId channel(const std::string& session, const char* event) {
    return {"afhub", "bench/" + session, event};
  }
  RawWriter writer_;
  RawLatestReader reader_;
};

}  // namespace

std::unique_ptr<Transport> open_afhub_transport(Side side, const std::string& session) {
  connect_to_hub(side == Side::kPing ? "bench" : "bench-peer", HubPolicy::kAutostart);
  return std::make_unique<AfhubTransport>(side, session);
}

}  // namespace afhub::bench
