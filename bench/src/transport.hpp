// One end of the ping-pong `afhub bench` times over each transport. The bench
// process is the ping side; a peer process it starts is the pong side. Every
// message is exactly `bytes` long and starts with the round and two stamps.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "afhub/shm_layout/header.hpp"

namespace afhub::bench {

enum class TransportKind { kAfhub, kAfhubSlot, kShmFloor, kDds, kDdsShm, kUds, kRos1 };
enum class Side { kPing, kPong };

struct Message {
  std::uint32_t bytes = 0;
  std::uint64_t round = 0;
  std::int64_t send_ns = 0;          // stamped by the sender just before sending
  std::int64_t peer_receive_ns = 0;  // pong: when the peer had the ping
  std::int64_t receive_ns = 0;       // stamped by the receiver once the whole message is in
};

// What every message starts with, on transports that carry plain bytes.
struct Stamps {
  std::uint64_t round;
  std::int64_t send_ns;
  std::int64_t peer_receive_ns;
};

class Transport {
 public:
  virtual ~Transport() = default;
  // --touch: the sender writes every byte of a message after its stamps and the
  // receiver reads every one (checking them) before it stamps the arrival. Off, only
  // the stamps are written and read (iceoryx's iceperf convention).
  void set_touch(bool touch) { touch_ = touch; }
  // After the peer process started: accept or wait for it (until deadline_ns).
  virtual void connect(std::int64_t /*deadline_ns*/) {}
  // Sends `bytes` bytes; returns the send stamp written into the message.
  virtual std::int64_t send(std::uint32_t bytes, std::uint64_t round,
                            std::int64_t peer_receive_ns) = 0;
  // The next message, or nothing when none came before deadline_ns.
  virtual std::optional<Message> receive(std::int64_t deadline_ns) = 0;

 protected:
  // With --touch: writes the `bytes` bytes at `at` (a pattern of the round), or reads
  // them all and throws afhub::Error, naming `transport`, when one differs.
  void touch_written(char* at, std::size_t bytes, std::uint64_t round) const;
  void touch_read(const char* at, std::size_t bytes, std::uint64_t round,
                  const char* transport) const;

 private:
  bool touch_ = false;
};

const char* transport_name(TransportKind kind);
std::optional<TransportKind> parse_transport(const std::string& name);
// Why a transport cannot run in this build or on this machine; empty when it can.
std::string transport_unavailable(TransportKind kind);

// `session` names this bench run's channels, topics and socket; `touch`, see
// Transport::set_touch. Throws afhub::Error.
std::unique_ptr<Transport> open_transport(TransportKind kind, Side side, const std::string& session,
                                          bool touch);

// The largest payload and the smallest message (the round and the stamps must fit).
inline constexpr std::uint32_t kMaxPayloadBytes = 1u << 20;
inline constexpr std::uint32_t kMinPayloadBytes = 64;

// The transports, each in its own file.
// A queue of samples, or (`slot`) a latest-value slot.
std::unique_ptr<Transport> open_afhub_transport(Side side, const std::string& session, bool slot);
// Bare shared memory, no afhub code: the floor of the slots' figures.
std::unique_ptr<Transport> open_floor_transport(Side side, const std::string& session);
std::unique_ptr<Transport> open_uds_transport(Side side, const std::string& session);
// `shared_memory`: Cyclone's iceoryx transport through the running hub (dds-shm).
std::unique_ptr<Transport> open_dds_transport(Side side, const std::string& session,
                                              bool shared_memory);
std::unique_ptr<Transport> open_ros1_transport(Side side, const std::string& session);

}  // namespace afhub::bench
