// Releasing iceoryx port locks held by dead threads (see port_lock_repair.hpp).
#include "port_lock_repair.hpp"

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <set>
#include <type_traits>
#include <vector>

#include "iceoryx_posh/internal/popo/building_blocks/locking_policy.hpp"
#include "iceoryx_posh/roudi/port_pool.hpp"
#include "liveness.hpp"

namespace afhub {
namespace {

using iox::popo::ThreadSafePolicy;

// ThreadSafePolicy's one (private) member is a posix::mutex, whose one member is
// the public pthread mutex: the three share an address. Checked for this build.
static_assert(std::is_standard_layout_v<ThreadSafePolicy> &&
                  sizeof(ThreadSafePolicy) == sizeof(iox::posix::mutex) &&
                  sizeof(iox::posix::mutex) == sizeof(pthread_mutex_t),
              "iceoryx's ThreadSafePolicy is no longer a bare pthread mutex: revisit this repair");

// The thread that holds `mutex`, when it no longer runs here; 0 when none does.
pid_t dead_owner(pthread_mutex_t& mutex) {
  if (std::atomic_ref<int>(mutex.__data.__lock).load() == 0) return 0;
  const pid_t tid = std::atomic_ref<int>(mutex.__data.__owner).load();
  return tid > 0 && task_is_gone(tid) ? tid : 0;
}

}  // namespace

pthread_mutex_t& native_mutex(const ThreadSafePolicy& policy) {
  return const_cast<pthread_mutex_t&>(reinterpret_cast<const iox::posix::mutex&>(policy).m_handle);
}

pid_t release_if_owner_died(pthread_mutex_t& mutex) {
  // glibc's layout of a normal or recursive, non-robust mutex: __lock is 0 when
  // free, 1 when held, 2 when held with waiters; __owner is the holder's thread id,
  // cleared by its unlock before __lock is.
  auto& data = mutex.__data;
  std::atomic_ref<int> lock(data.__lock);
  std::atomic_ref<int> owner(data.__owner);
  pid_t tid = dead_owner(mutex);
  if (tid == 0) return 0;
  // Still that thread's: had it unlocked before dying, __owner would have changed.
  if (!owner.compare_exchange_strong(tid, 0)) return 0;
  // The rest of the unlock the owner never reached.
  data.__count = 0;
  if (data.__nusers > 0) --data.__nusers;
  if (lock.exchange(0) > 1)  // waiters sleep on the futex: process-shared, so no private flag
    syscall(SYS_futex, &data.__lock, FUTEX_WAKE, INT_MAX, nullptr, nullptr, 0);
  return tid;
}

std::size_t release_port_locks_of_dead_threads(iox::roudi::PortPool& ports,
                                               const ThreadIdsAreLocal& ids_are_local) {
  struct Held {
    pthread_mutex_t* mutex;
    const char* what;
  };
  std::vector<Held> held;
  for (auto* publisher : ports.getPublisherPortDataList())
    if (pthread_mutex_t& mutex = native_mutex(publisher->m_chunkSenderData); dead_owner(mutex))
      held.push_back({&mutex, "publisher"});
  for (auto* subscriber : ports.getSubscriberPortDataList())
    if (pthread_mutex_t& mutex = native_mutex(subscriber->m_chunkReceiverData); dead_owner(mutex))
      held.push_back({&mutex, "subscriber queue"});
  if (held.empty()) return 0;
  // Only ids were read: they are judged when every process with a port has ids of
  // this pid namespace. Its ports looked at after the locks, a thread that held one
  // had a port of its own process listed by then.
  std::set<std::string> runtimes;
  for (auto* publisher : ports.getPublisherPortDataList())
    runtimes.insert(publisher->m_runtimeName.c_str());
  for (auto* subscriber : ports.getSubscriberPortDataList())
    runtimes.insert(subscriber->m_runtimeName.c_str());
  for (const std::string& runtime : runtimes)
    if (!ids_are_local(runtime)) return 0;
  std::size_t released = 0;
  for (const Held& lock : held) {
    if (pid_t tid = release_if_owner_died(*lock.mutex)) {
      std::fprintf(stderr,
                   "afhub hub: thread %d died holding a %s lock inside iceoryx (a client killed "
                   "mid-publish); released it so the hub and the other clients keep running\n",
                   static_cast<int>(tid), lock.what);
      ++released;
    }
  }
  return released;
}

}  // namespace afhub
