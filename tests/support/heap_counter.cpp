// The counting operator new (see heap_counter.hpp).
#include "heap_counter.hpp"

#include <unistd.h>

#include <cstdlib>
#include <new>

// The replacements below pair malloc with free on purpose; GCC cannot see that.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

namespace {

std::atomic<long> g_allocations{0};
thread_local long t_allocations = 0;
thread_local std::atomic<long>* t_also = nullptr;
// One thread watched from another: its id, and where its allocations go.
std::atomic<pid_t> g_watched_tid{0};
std::atomic<std::atomic<long>*> g_watched_counter{nullptr};

#if defined(AFHUB_SANITIZED)
// The sanitizers own malloc.
void* raw_malloc(std::size_t size) {
  return std::malloc(size);
}
#else
// glibc's allocator under its internal name, which malloc_counter.cpp does not count
// again.
extern "C" void* __libc_malloc(std::size_t);
void* raw_malloc(std::size_t size) {
  return __libc_malloc(size);
}
#endif

}  // namespace

namespace afhub::test {

void note_heap_allocation() noexcept {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  ++t_allocations;
  if (t_also) t_also->fetch_add(1, std::memory_order_relaxed);
  if (std::atomic<long>* watched = g_watched_counter.load(std::memory_order_acquire)) {
    thread_local const pid_t tid = gettid();
    if (tid == g_watched_tid.load(std::memory_order_relaxed))
      watched->fetch_add(1, std::memory_order_relaxed);
  }
}

long heap_allocations() noexcept {
  return g_allocations.load(std::memory_order_relaxed);
}

long thread_heap_allocations() noexcept {
  return t_allocations;
}

void count_thread_allocations_into(std::atomic<long>* counter) noexcept {
  t_also = counter;
}

void count_allocations_of_thread(pid_t tid, std::atomic<long>* counter) noexcept {
  g_watched_counter.store(nullptr, std::memory_order_release);
  g_watched_tid.store(tid, std::memory_order_relaxed);
  g_watched_counter.store(counter, std::memory_order_release);
}

}  // namespace afhub::test

void* operator new(std::size_t size) {
  afhub::test::note_heap_allocation();
  if (void* p = raw_malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) {
  return operator new(size);
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  afhub::test::note_heap_allocation();
  return raw_malloc(size ? size : 1);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept {
  return operator new(size, tag);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
