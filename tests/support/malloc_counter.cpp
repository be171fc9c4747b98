// Counts the C allocations (malloc, calloc, realloc) of the test binary it is linked
// into as heap_counter.hpp's allocations, beside operator new's. Not under the
// sanitizers, which own malloc: there only C++ allocations count.
#include "heap_counter.hpp"

#if !defined(AFHUB_SANITIZED)
#include <cstddef>

// glibc's allocator under its internal names; the public ones are replaced here.
extern "C" void* __libc_malloc(std::size_t);
extern "C" void* __libc_calloc(std::size_t, std::size_t);
extern "C" void* __libc_realloc(void*, std::size_t);

extern "C" void* malloc(std::size_t size) {
  afhub::test::note_heap_allocation();
  return __libc_malloc(size);
}
extern "C" void* calloc(std::size_t count, std::size_t size) {
  afhub::test::note_heap_allocation();
  return __libc_calloc(count, size);
}
extern "C" void* realloc(void* p, std::size_t size) {
  afhub::test::note_heap_allocation();
  return __libc_realloc(p, size);
}
#endif
