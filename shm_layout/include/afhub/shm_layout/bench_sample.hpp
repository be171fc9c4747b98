// BenchSample: the ping and the pong of `afhub bench`. The chunk is as long as the
// payload size measured (64 bytes to 1 MiB); these fields start it and the rest is
// left as it is: a zero-copy writer fills its data in place, so sending costs the
// same whatever the size.
#pragma once

#include <cstdint>

#include "afhub/shm_layout/header.hpp"

namespace afhub {

struct BenchSample {
  static constexpr PayloadKind kKind = PayloadKind::kBenchSample;
  PayloadHeader header;             // publish_stamp_ns is the send time
  std::uint64_t round{0};           // which ping this is, or which ping a pong answers
  std::int64_t peer_receive_ns{0};  // pong: when the peer received the ping (CLOCK_MONOTONIC)
};

}  // namespace afhub
