// BenchSample: the ping and the pong of `afhub bench`. The chunk is as long as the
// payload size measured (64 bytes to 1 MiB); these fields start it and the rest is
// left as it is (a zero-copy writer fills its data in place, so sending costs the
// same whatever the size), or with --touch written and read whole.
#pragma once

#include <cstdint>

#include "afhub/shm_layout/header.hpp"

namespace afhub {

struct BenchSample {
  static constexpr PayloadKind kKind = PayloadKind::kBenchSample;
  PayloadHeader header;             // header.sim_step: which ping this is, or which a pong answers
  std::int64_t send_ns{0};          // when the sender began it, before its loan (CLOCK_MONOTONIC)
  std::int64_t peer_receive_ns{0};  // pong: when the peer received the ping
};

// The smallest sample measured (64 bytes) holds it whole.
static_assert(sizeof(BenchSample) <= 64);

}  // namespace afhub
