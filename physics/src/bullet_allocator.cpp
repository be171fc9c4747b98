#include "bullet_allocator.hpp"

#include <LinearMath/btAlignedAllocator.h>
#include <malloc.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <cstring>

namespace afhub::physics {
namespace {

// Enough for the two arrays of a few soft bodies of different sizes; blocks larger than
// kLargest (a soft body of about 30 000 nodes) are left to malloc, so that a thread
// holds 8 MiB at most.
constexpr std::size_t kBlocks = 8;
constexpr std::size_t kLargest = std::size_t{1} << 20;

// Trivially destructible, so that it is still usable in whatever runs after a thread's
// destructors (freeing goes straight to free() once `closed`).
struct Cache {
  std::array<void*, kBlocks> blocks;
  std::size_t count;
  bool closed;
};
thread_local Cache t_cache{};

// Returns the thread's blocks to malloc when it ends.
struct CacheCloser {
  ~CacheCloser() {
    t_cache.closed = true;
    for (std::size_t i = 0; i < t_cache.count; ++i) std::free(t_cache.blocks[i]);
    t_cache.count = 0;
  }
};

Cache& thread_cache() {
  thread_local CacheCloser closer;  // registered on the thread's first use
  (void)closer;
  return t_cache;
}

void* allocate(std::size_t size) {
  Cache& cache = thread_cache();
  for (std::size_t i = cache.count; i-- > 0;) {
    void* block = cache.blocks[i];
    const std::size_t usable = malloc_usable_size(block);
    // The same request as a block freed before gets the same size class from malloc.
    if (usable >= size && usable <= size + 64) {
      std::copy(cache.blocks.begin() + i + 1, cache.blocks.begin() + cache.count,
                cache.blocks.begin() + i);
      --cache.count;
      std::memset(block, 0, size);  // as Bullet's own allocator hands memory out
      return block;
    }
  }
  return std::calloc(1, size);
}

// The newest blocks are kept, the oldest freed to make room: a block freed once and
// never asked for again (a world's teardown, a pair of objects that parted) does not
// keep a step's scratch out.
void release(void* block) {
  Cache& cache = thread_cache();
  if (!block || cache.closed || malloc_usable_size(block) > kLargest) {
    std::free(block);
    return;
  }
  if (cache.count == kBlocks) {
    std::free(cache.blocks[0]);
    std::copy(cache.blocks.begin() + 1, cache.blocks.end(), cache.blocks.begin());
    --cache.count;
  }
  cache.blocks[cache.count++] = block;
}

}  // namespace

void reuse_bullet_scratch() {
  static const bool installed = [] {
    btAlignedAllocSetCustom(allocate, release);
    return true;
  }();
  (void)installed;
}

}  // namespace afhub::physics
