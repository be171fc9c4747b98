// Releases iceoryx port locks left held by a thread that died.
//
// iceoryx 2.0.3 guards each publisher's subscriber list and each subscriber's
// queue with a process-shared pthread mutex that is not robust. A client killed
// inside publish() (SIGKILL, a crash) keeps that lock forever: the next publisher
// pushing into the queue blocks, and RouDi blocks when it cleans up after the dead
// client, holding its process table, so no client can register or be served again
// (iceoryx issues #2193 and #2276). The hub runs RouDi, so it repairs what a robust
// mutex would have: a lock whose owner thread is gone is released and its waiters
// are woken.
//
// A thread id means what it says only in its own pid namespace: one of another
// namespace may be missing from the hub's /proc while its thread runs. So locks are
// judged only while every process with a port is one whose ids are the hub's.
#pragma once

#include <pthread.h>
#include <sys/types.h>

#include <cstddef>
#include <functional>
#include <string>

namespace iox::roudi {
class PortPool;
}
namespace iox::popo {
class ThreadSafePolicy;
}

namespace afhub {

// The pthread mutex inside an iceoryx port's locking policy.
pthread_mutex_t& native_mutex(const iox::popo::ThreadSafePolicy& policy);

// Releases `mutex` if it is locked by a thread that no longer runs (gone, or a
// zombie); returns that thread's id, or 0 when it left the mutex alone.
pid_t release_if_owner_died(pthread_mutex_t& mutex);

// Whether the thread ids of the process registered as `runtime` are those of the
// hub's pid namespace (or it is gone, with all its threads).
using ThreadIdsAreLocal = std::function<bool(const std::string& runtime)>;

// Checks every publisher's and subscriber's lock; when some look held by a dead
// thread and every port's process has local thread ids, releases them, reports
// each on stderr and returns how many. Cheap when nothing is held: no system call.
std::size_t release_port_locks_of_dead_threads(iox::roudi::PortPool& ports,
                                               const ThreadIdsAreLocal& ids_are_local);

}  // namespace afhub
