// Counts every C++ heap allocation of the test binary it is linked into (its
// operator new replaces the standard one), for tests that a cycle allocates nothing:
//   const long before = heap_allocations();  ...  EXPECT_EQ(heap_allocations(), before);
// Linking malloc_counter.cpp as well counts C allocations (malloc, calloc, realloc).
#pragma once

#include <sys/types.h>

#include <atomic>

namespace afhub::test {

// Every thread's allocations since the binary started.
long heap_allocations() noexcept;
// The calling thread's: other threads (iceoryx's, the sanitizers') do not count.
long thread_heap_allocations() noexcept;
// Adds the calling thread's allocations from now on to `counter` too, so that another
// thread reads them; nullptr stops.
void count_thread_allocations_into(std::atomic<long>* counter) noexcept;
// The same for the thread whose id (gettid) is `tid`, from another thread: a thread
// the code under test started. Counts into `counter` until called with nullptr.
void count_allocations_of_thread(pid_t tid, std::atomic<long>* counter) noexcept;

// One allocation, counted: for the replaced allocation functions.
void note_heap_allocation() noexcept;

}  // namespace afhub::test
