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
#pragma once

#include <pthread.h>
#include <sys/types.h>

#include <cstddef>

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

// Checks every publisher's and subscriber's lock; reports each release on stderr
// and returns how many it released. Cheap when nothing is held: no system call.
std::size_t release_port_locks_of_dead_threads(iox::roudi::PortPool& ports);

}  // namespace afhub
