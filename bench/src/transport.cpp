// Transport names and the choice of an implementation (see transport.hpp).
#include "transport.hpp"

#include <time.h>
#include <unistd.h>

#include <cstring>

#include "afhub/shm_layout/error.hpp"

namespace afhub::bench {

const char* transport_name(TransportKind kind) {
  switch (kind) {
    case TransportKind::kAfhub:
      return "afhub";
    case TransportKind::kAfhubSlot:
      return "afhub-slot";
    case TransportKind::kShmFloor:
      return "shm-floor";
    case TransportKind::kDds:
      return "dds";
    case TransportKind::kDdsShm:
      return "dds-shm";
    case TransportKind::kUds:
      return "uds";
    case TransportKind::kRos1:
      return "ros1";
  }
  return "?";
}

std::optional<TransportKind> parse_transport(const std::string& name) {
  for (TransportKind kind :
       {TransportKind::kAfhub, TransportKind::kAfhubSlot, TransportKind::kShmFloor,
        TransportKind::kDds, TransportKind::kDdsShm, TransportKind::kUds, TransportKind::kRos1})
    if (name == transport_name(kind)) return kind;
  return std::nullopt;
}

std::string transport_unavailable(TransportKind kind) {
  if (kind == TransportKind::kRos1) {
#ifndef AFHUB_BENCH_ROS1
    return "not built: Debian's libroscpp-dev, libstd-msgs-dev and python3-rosmaster were not "
           "installed when afhub was configured (install them and rebuild)";
#else
    if (access("/usr/bin/rosmaster", X_OK) != 0)
      return "rosmaster not found: install Debian's python3-rosmaster";
#endif
  }
  return "";
}

std::unique_ptr<Transport> open_transport(TransportKind kind, Side side, const std::string& session,
                                          bool touch) {
  const std::string unavailable = transport_unavailable(kind);
  if (!unavailable.empty()) throw Error(std::string(transport_name(kind)) + ": " + unavailable);
  std::unique_ptr<Transport> opened;
  switch (kind) {
    case TransportKind::kAfhub:
    case TransportKind::kAfhubSlot:
      opened = open_afhub_transport(side, session, kind == TransportKind::kAfhubSlot);
      break;
    case TransportKind::kDds:
    case TransportKind::kDdsShm:
      opened = open_dds_transport(side, session, kind == TransportKind::kDdsShm);
      break;
    case TransportKind::kShmFloor:
      opened = open_floor_transport(side, session);
      break;
    case TransportKind::kUds:
      opened = open_uds_transport(side, session);
      break;
    case TransportKind::kRos1:
#ifdef AFHUB_BENCH_ROS1
      opened = open_ros1_transport(side, session);
#endif
      break;
  }
  if (!opened) throw Error("unknown transport");
  opened->set_touch(touch);
  return opened;
}

void Transport::touch_written(char* at, std::size_t bytes, std::uint64_t round) const {
  if (touch_) std::memset(at, static_cast<int>(round & 0xffU), bytes);
}

void Transport::touch_read(const char* at, std::size_t bytes, std::uint64_t round,
                           const char* transport) const {
  if (!touch_) return;
  // Every byte read, none skipped, eight at a time (a consumer reads at memory speed):
  // the differences are gathered, not searched for.
  const auto expected = static_cast<unsigned char>(round & 0xffU);
  const std::uint64_t pattern = 0x0101010101010101ULL * expected;
  std::uint64_t differ = 0;
  std::size_t i = 0;
  for (; i + sizeof pattern <= bytes; i += sizeof pattern) {
    std::uint64_t word;
    std::memcpy(&word, at + i, sizeof word);
    differ |= word ^ pattern;
  }
  for (; i < bytes; ++i) differ |= static_cast<unsigned char>(at[i]) ^ expected;
  if (differ == 0) return;
  std::size_t changed = 0;
  for (i = 0; i < bytes; ++i) changed += static_cast<unsigned char>(at[i]) != expected ? 1 : 0;
  throw Error(std::string(transport) + ": " + std::to_string(changed) + " of " +
              std::to_string(bytes) + " bytes of round " + std::to_string(round) +
              " arrived changed");
}
}  // namespace afhub::bench
