// Bullet's heap memory, through a small per-thread cache of the blocks it last freed.
// A soft body's step makes and frees two scratch arrays twice
// (btSoftBody::applyClusters, even for a soft body without clusters): 4 heap
// allocations a step, each now served by the block the step before freed. Every other
// allocation is malloc's, as before; a thread keeps the 8 blocks of up to 1 MiB it freed
// last.
#pragma once

namespace afhub::physics {

// Hands Bullet's allocations (btAlignedAllocSetCustom) to the cache, once a process.
// The cache holds plain malloc blocks, so blocks Bullet took before, from malloc, are
// freed through it alike.
void reuse_bullet_scratch();

}  // namespace afhub::physics
