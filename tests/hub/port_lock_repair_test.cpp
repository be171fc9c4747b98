// The hub's repair of locks left held by dead threads, on plain process-shared
// recursive mutexes like iceoryx's (no hub needed).
#include "port_lock_repair.hpp"

#include <gtest/gtest.h>
#include <pthread.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <thread>

namespace afhub {
namespace {

using namespace std::chrono_literals;

struct SharedRecursiveMutex {
  SharedRecursiveMutex() {
    pthread_mutexattr_t attributes;
    pthread_mutexattr_init(&attributes);
    pthread_mutexattr_setpshared(&attributes, PTHREAD_PROCESS_SHARED);
    pthread_mutexattr_settype(&attributes, PTHREAD_MUTEX_RECURSIVE);
    pthread_mutex_init(&mutex, &attributes);
    pthread_mutexattr_destroy(&attributes);
  }
  ~SharedRecursiveMutex() { pthread_mutex_destroy(&mutex); }
  bool held_by_someone_else() {
    int result = EBUSY;
    std::thread([&] {
      result = pthread_mutex_trylock(&mutex);
      if (result == 0) pthread_mutex_unlock(&mutex);
    }).join();
    return result == EBUSY;
  }
  pthread_mutex_t mutex;
};

TEST(PortLockRepair, ReleasesALockWhoseOwnerDiedAndWakesItsWaiter) {
  SharedRecursiveMutex shared;
  pid_t dead_owner = 0;
  std::thread([&] {
    pthread_mutex_lock(&shared.mutex);
    pthread_mutex_lock(&shared.mutex);  // recursive: a count of two to undo
    dead_owner = gettid();
  }).join();  // ends holding it
  ASSERT_TRUE(shared.held_by_someone_else());

  std::atomic<bool> waiter_got_it{false};
  std::thread waiter([&] {
    pthread_mutex_lock(&shared.mutex);
    waiter_got_it = true;
    pthread_mutex_unlock(&shared.mutex);
  });
  std::this_thread::sleep_for(50ms);  // asleep on the lock by now
  EXPECT_FALSE(waiter_got_it);

  EXPECT_EQ(release_if_owner_died(shared.mutex), dead_owner);
  const auto deadline = std::chrono::steady_clock::now() + 2s;
  while (!waiter_got_it && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(1ms);
  if (!waiter_got_it) {
    waiter.detach();  // still asleep on the lock: the repair did not wake it
    FAIL() << "the waiter was not woken";
  }
  waiter.join();
  EXPECT_FALSE(shared.held_by_someone_else());
  EXPECT_EQ(release_if_owner_died(shared.mutex), 0) << "a free lock is left alone";
}

TEST(PortLockRepair, LeavesALockOfALiveThreadAlone) {
  SharedRecursiveMutex shared;
  pthread_mutex_lock(&shared.mutex);
  EXPECT_EQ(release_if_owner_died(shared.mutex), 0);
  EXPECT_TRUE(shared.held_by_someone_else());
  pthread_mutex_unlock(&shared.mutex);
}

}  // namespace
}  // namespace afhub
