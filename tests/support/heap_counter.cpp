// The counting operator new (see heap_counter.hpp).
#include "heap_counter.hpp"

#include <atomic>
#include <cstdlib>
#include <new>

// The replacements below pair malloc with free on purpose; GCC cannot see that.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}

namespace afhub::test {

long heap_allocations() noexcept {
  return g_allocations.load(std::memory_order_relaxed);
}

}  // namespace afhub::test
