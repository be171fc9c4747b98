// Transport names and the choice of an implementation (see transport.hpp).
#include "transport.hpp"

#include <time.h>
#include <unistd.h>

#include "afhub/shm_layout/error.hpp"

namespace afhub::bench {

const char* transport_name(TransportKind kind) {
  switch (kind) {
    case TransportKind::kAfhub:
      return "afhub";
    case TransportKind::kAfhubSlot:
      return "afhub-slot";
    case TransportKind::kDds:
      return "dds";
    case TransportKind::kUds:
      return "uds";
    case TransportKind::kRos1:
      return "ros1";
  }
  return "?";
}

std::optional<TransportKind> parse_transport(const std::string& name) {
  for (TransportKind kind : {TransportKind::kAfhub, TransportKind::kAfhubSlot, TransportKind::kDds,
                             TransportKind::kUds, TransportKind::kRos1})
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

std::unique_ptr<Transport> open_transport(TransportKind kind, Side side,
                                          const std::string& session) {
  const std::string unavailable = transport_unavailable(kind);
  if (!unavailable.empty()) throw Error(std::string(transport_name(kind)) + ": " + unavailable);
  switch (kind) {
    case TransportKind::kAfhub:
    case TransportKind::kAfhubSlot:
      return open_afhub_transport(side, session, kind == TransportKind::kAfhubSlot);
    case TransportKind::kDds:
      return open_dds_transport(side, session);
    case TransportKind::kUds:
      return open_uds_transport(side, session);
    case TransportKind::kRos1:
#ifdef AFHUB_BENCH_ROS1
      return open_ros1_transport(side, session);
#endif
      break;
  }
  throw Error("unknown transport");
}

}  // namespace afhub::bench
