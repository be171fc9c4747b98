// Fixed capacities of every payload. Payloads live in shared memory mapped at a
// different address in each process, so nothing in them may grow: each bound is
// chosen here once, with the reason beside it.
#pragma once

#include <cstddef>
#include <cstdint>

namespace afhub {

// Descendant joints reported by one body. AMBF reports every joint below a body;
// the largest seed models (da Vinci PSM with its parallel linkage: about 15, a
// humanoid root: about 40) fit with room to spare, and a state stays under 2 KB.
inline constexpr std::size_t kMaxJointsPerBody = 64;

// A body's channel name "<namespace>/<body>" is an iceoryx instance string,
// which holds at most 100 characters. The buffer keeps a terminating NUL.
inline constexpr std::size_t kMaxChannelNameLength = 100;
inline constexpr std::size_t kChannelNameBufferSize = 104;

// Joint names in AMBF models are short identifiers ("baselink-link1"); 63 characters
// covers generated names with namespaces while keeping a catalog entry near 4 KB.
inline constexpr std::size_t kMaxJointNameLength = 63;
inline constexpr std::size_t kJointNameBufferSize = 64;

// Process (iceoryx runtime) names are limited to 100 characters by iceoryx.
inline constexpr std::size_t kProcessNameBufferSize = 104;

// Bodies in the catalog. iceoryx 2.0 allows 512 publishers in the whole system and
// every active body needs a state publisher and at least one command publisher.
inline constexpr std::size_t kMaxBodies = 256;

// Proximity-sensor rays reported in one body's state (AMBF's parametric sensors
// are resolution^2 rays; 32 covers a 5x5 grid and several small arrays).
inline constexpr std::size_t kMaxSensorRaysPerBody = 32;

// Constraint actuators one body command can drive.
inline constexpr std::size_t kMaxActuatorsPerBody = 8;

// Lights and cameras whose poses the world state carries.
inline constexpr std::size_t kMaxWorldObjects = 8;

// Processes listed in the hub's health. iceoryx allows 300 runtimes; a co-simulation
// rarely has more than a few dozen, and the health payload stays small.
inline constexpr std::size_t kMaxHealthProcesses = 64;

// iceoryx 2.0 supports at most 32 mempools per segment.
inline constexpr std::size_t kMaxMempools = 32;

}  // namespace afhub
