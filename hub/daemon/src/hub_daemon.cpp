// The hub daemon (see hub_daemon.hpp): one lock file, RouDi in this process, the
// catalog and health publishers, and a clean stop on SIGINT or SIGTERM.
#include "afhub/hub/hub_daemon.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include <grp.h>
#include <sys/random.h>
#include <sys/stat.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <optional>
#include <set>
#include <string>
#include <thread>

#include "afhub/hub/hub_files.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/process_claim.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub_roudi.hpp"
#include "catalog_builder.hpp"
#include "health_reporter.hpp"
#include "iceoryx_hoofs/error_handling/error_handling.hpp"
#include "iceoryx_hoofs/posix_wrapper/posix_access_rights.hpp"
#include "iceoryx_posh/iceoryx_posh_config.hpp"
#include "iceoryx_posh/roudi/iceoryx_roudi_components.hpp"
#include "iceoryx_posh/roudi/port_pool.hpp"
#include "iceoryx_posh/runtime/posh_runtime_single_process.hpp"
#include "port_lock_repair.hpp"
#include "runtime_files.hpp"

namespace afhub {
namespace {

constexpr char kHubRuntimeName[] = "afhub-hub";

iox::RouDiConfig_t roudi_config(const std::vector<MempoolSpec>& pools, const std::string& group,
                                double& total_mib) {
  iox::mepoo::MePooConfig mempools;
  total_mib = 0.0;
  for (const MempoolSpec& pool : pools) {
    mempools.addMemPool({pool.payload_bytes, pool.chunk_count});
    total_mib += static_cast<double>(pool.payload_bytes) * pool.chunk_count / (1024.0 * 1024.0);
  }
  iox::RouDiConfig_t config;
  const iox::posix::PosixGroup::string_t name(iox::cxx::TruncateToCapacity, group.c_str());
  config.m_sharedMemorySegments.push_back({name, name, mempools});
  return config;
}

// The hub lock, released last: after RouDi is gone, so that a new hub can start at once.
struct HubLock {
  int fd = -1;
  ~HubLock() {
    if (fd >= 0) close(fd);
  }
};

// Writes "<pid> <instance> <pid namespace>" beside the lock, atomically (clients read it
// at any time).
bool write_hub_identity(const std::string& directory) {
  std::uint64_t instance = 0;
  while (instance == 0)
    if (getrandom(&instance, sizeof instance, 0) != sizeof instance) return false;
  const std::string text = std::to_string(getpid()) + " " + std::to_string(instance) + " " +
                           std::to_string(own_pid_namespace()) + "\n";
  const std::string path = hub_identity_path(directory), draft = path + ".new";
  unlink(draft.c_str());
  const int fd = open_own_file(draft, O_WRONLY | O_CREAT | O_EXCL, 0644);
  if (fd < 0) return false;
  const bool written = write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  close(fd);
  return written && rename(draft.c_str(), path.c_str()) == 0;
}

// Takes the hub lock (0600: no other user can hold it) and writes this hub's identity;
// -1 when another hub has the lock.
int take_hub_lock(const std::string& directory) {
  const int fd = open_own_file(hub_lock_path(directory), O_RDWR | O_CREAT, 0600);
  if (fd < 0) {
    std::fprintf(stderr, "afhub hub: cannot open %s: %s\n", hub_lock_path(directory).c_str(),
                 std::strerror(errno));
    return -1;
  }
  // Clients waiting to re-attach look at the lock (a shared flock for a moment) every
  // few ms: tried for 200 ms, a lock held all along is another hub's.
  int tries = 0;
  while (flock(fd, LOCK_EX | LOCK_NB) != 0) {
    if (++tries == 20) {
      close(fd);
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (!write_hub_identity(directory)) {
    std::fprintf(stderr, "afhub hub: cannot write %s: %s\n", hub_identity_path(directory).c_str(),
                 std::strerror(errno));
    close(fd);
    return -1;
  }
  return fd;
}

// The registered processes, as the serve loop follows them.
struct Registered {
  std::set<std::string> removed;  // asked for; RouDi's introspection may list them a moment longer
  std::set<std::string> foreign;  // in another pid namespace than the hub's
  // Listed, and in the hub's pid namespace (the hub among them): the thread ids in
  // their port locks mean what they say here.
  std::set<std::string> local;
};

// A runtime's thread ids can be judged in the hub's pid namespace when it runs there,
// or is gone with all its threads. Its threads take port locks up to a second before
// RouDi's introspection lists it: an afhub client is told by its name until then;
// any other runtime is not judged.
ThreadIdsAreLocal local_thread_ids(const Registered& registered) {
  return [&registered](const std::string& runtime) {
    return registered.local.count(runtime) > 0 || runtime_is_gone(runtime, 0) ||
           client_in_hub_pid_namespace(runtime);
  };
}

// Unregisters every process whose runtime lock is free: gone, in whatever pid
// namespace it ran. Port locks its threads died holding are released first: RouDi
// takes them to delete its ports, and would wait on them forever.
void remove_dead_processes(AfhubRouDi& roudi, iox::roudi::PortPool& ports, HealthReporter& health,
                           Registered& registered) {
  const auto processes = health.registered_processes();
  std::set<std::string> listed, gone;
  registered.local = {"roudi", kHubRuntimeName};
  for (const auto& [name, pid] : processes) {
    listed.insert(name);
    // RouDi's and the hub's own entries: a pid alone cannot tell them, since a client in
    // another pid namespace may have the hub's pid.
    if (registered.local.count(name) || registered.removed.count(name)) continue;
    if (runtime_is_gone(name, pid)) {
      gone.insert(name);
    } else if (runtime_in_hub_pid_namespace(name, pid)) {
      registered.local.insert(name);
    } else if (registered.foreign.insert(name).second) {
      std::fprintf(stderr,
                   "afhub hub: %s runs in another pid namespace; while it is attached, the hub "
                   "cannot tell whose thread holds a port lock, and repairs none\n",
                   name.c_str());
    }
  }
  const auto unlisted = [&](const std::string& name) { return !listed.count(name); };
  std::erase_if(registered.removed, unlisted);
  std::erase_if(registered.foreign, unlisted);
  if (!gone.empty()) release_port_locks_of_dead_threads(ports, local_thread_ids(registered));
  for (const auto& [name, pid] : processes) {
    if (!gone.count(name)) continue;
    registered.removed.insert(name);
    if (roudi.remove_process(name))
      std::fprintf(stderr, "afhub hub: %s (pid %d) is gone; removed its ports and chunks\n",
                   name.c_str(), static_cast<int>(pid));
  }
}

void serve_until_stopped(AfhubRouDi& roudi, iox::roudi::PortPool& ports) {
  CatalogBuilder catalog;
  HealthReporter health;
  Registered registered;
  bool catalog_failed = false;
  auto next_file_sweep = std::chrono::steady_clock::now();
  while (!stop_requested()) {
    auto now = std::chrono::steady_clock::now();
    // Also each cycle: a publisher blocks on a queue's lock left by a dead thread before
    // its process is seen gone.
    remove_dead_processes(roudi, ports, health, registered);
    release_port_locks_of_dead_threads(ports, local_thread_ids(registered));
    if (now >= next_file_sweep) {
      for (const std::string& name : remove_stale_runtime_files())
        std::fprintf(stderr, "afhub hub: removed the files %s left in /tmp\n", name.c_str());
      next_file_sweep = now + std::chrono::seconds(1);
    }
    // The hub's own readers (rate probes, directories) check this count, as any
    // process's do: iceoryx would abort the hub, and RouDi with it, at the last port.
    const auto free_subscribers =
        static_cast<std::uint32_t>(iox::MAX_SUBSCRIBERS - ports.getSubscriberPortDataList().size());
    count_subscriber_ports_from(free_subscribers);
    // What other processes publish must never stop the hub (and RouDi with it).
    try {
      catalog.poll(now);
    } catch (const std::exception& error) {
      if (!catalog_failed)
        std::fprintf(stderr, "afhub hub: the catalog was not updated: %s (said once)\n",
                     error.what());
      catalog_failed = true;
    }
    const auto publishers = static_cast<std::uint32_t>(ports.getPublisherPortDataList().size());
    const auto subscribers = static_cast<std::uint32_t>(ports.getSubscriberPortDataList().size());
    health.poll(now, catalog.body_count(),
                {iox::MAX_PUBLISHERS - publishers, iox::MAX_SUBSCRIBERS - subscribers});
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

}  // namespace

// iceoryx's own locks in /tmp, which RouDi takes after it made its shared memory: one
// another user created or holds would abort it there, leaving that memory behind.
bool iceoryx_locks_are_free() {
  for (const char* path : {"/tmp/roudi.lock", "/tmp/iox-unique-roudi.lock"}) {
    struct stat info {};
    if (lstat(path, &info) != 0) continue;
    const char* problem = nullptr;
    // Held, it may be a hub that is ending: its lock freed, the process not yet gone
    // (CI: a hub started right after `afhub hub stop` found it held, and gave up).
    const auto released = [path] {
      for (int waited_ms = 0; flock_held(path); waited_ms += 50) {
        if (waited_ms >= 5000) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
      return true;
    };
    if (!S_ISREG(info.st_mode) || info.st_uid != geteuid())
      problem = "belongs to another user (planted there?)";
    else if (!released())
      problem = "is held by another process";
    if (!problem) continue;
    const std::optional<pid_t> holder = flock_holder(path);
    std::fprintf(stderr,
                 "afhub hub: iceoryx's lock %s %s (uid %u%s); RouDi could not start. Stop that "
                 "process, or remove the file as root, then start the hub again.\n",
                 path, problem, static_cast<unsigned>(info.st_uid),
                 holder ? (", held by pid " + std::to_string(*holder)).c_str() : "");
    return false;
  }
  return true;
}

// The hub's shared memory: the management segment and one payload segment, named
// after its group.
void remove_shared_memory(const std::string& group) {
  unlink("/dev/shm/iceoryx_mgmt");
  unlink(("/dev/shm/" + group).c_str());
}

// Lets `group` use what RouDi made for its own group: its management segment and its
// socket (the payload segment has the group in its ACL, from the config).
// RouDi makes its socket in a thread of its own: waited for, up to 2 s.
bool open_to_group(gid_t gid) {
  for (int tries = 0; access("/tmp/roudi", F_OK) != 0 && tries < 200; ++tries)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  for (const char* path : {"/dev/shm/iceoryx_mgmt", "/tmp/roudi"})
    if (chown(path, static_cast<uid_t>(-1), gid) != 0 || chmod(path, 0660) != 0) {
      std::fprintf(stderr, "afhub hub: cannot give %s to the hub's group: %s\n", path,
                   std::strerror(errno));
      return false;
    }
  return true;
}

std::string g_starting_group;  // the segment to remove when RouDi fails to start

int run_hub_daemon(const HubOptions& options) {
  std::string group = options.group;
  gid_t gid = getegid();
  if (group.empty()) {
    group = iox::posix::PosixGroup::getGroupOfCurrentProcess().getName().c_str();
  } else {
    const struct group* entry = getgrnam(group.c_str());
    if (!entry) {
      std::fprintf(stderr, "afhub hub: no group '%s' on this machine (see /etc/group)\n",
                   group.c_str());
      return 1;
    }
    gid = entry->gr_gid;
    // iceoryx lets a user write a segment when /etc/group makes it a member of the
    // segment's group: the hub writes its catalog and health there too.
    const iox::posix::PosixUser me = iox::posix::PosixUser::getUserOfCurrentProcess();
    bool member = false;
    for (const auto& own : me.getGroups()) member = member || own.getID() == gid;
    if (!member) {
      std::fprintf(stderr,
                   "afhub hub: the hub's user (%s) is not a member of the group '%s', and "
                   "iceoryx lets only members use its memory. Add it (`usermod -aG %s %s`) and "
                   "start the hub again.\n",
                   me.getName().c_str(), group.c_str(), group.c_str(), me.getName().c_str());
      return 1;
    }
  }
  HubLock lock{take_hub_lock(own_hub_directory())};
  if (lock.fd < 0) {
    auto pid = running_hub_pid();
    std::fprintf(stderr,
                 "afhub hub: a hub is already running (pid %d); there can be one per machine. "
                 "Use it, or stop it with `afhub hub stop`.\n",
                 pid ? static_cast<int>(*pid) : -1);
    return 1;
  }
  if (probe_roudi() == RoudiPresence::kRunning) {
    std::fprintf(stderr,
                 "afhub hub: another iceoryx RouDi (not an afhub hub, e.g. iox-roudi) is running; "
                 "iceoryx allows one per machine. Stop it, then run `afhub hub` again.\n");
    return 1;
  }
  if (!iceoryx_locks_are_free()) return 1;
  install_stop_signal_handlers();
  quiet_iceoryx_logs();

  // RouDi's socket and management segment take the group they are made with (0660),
  // and RouDi makes its socket in a thread of its own: the hub keeps `gid` as its
  // effective group for good (root may), else gives them the group once they exist.
  const gid_t own_gid = getegid();
  // iceoryx sets the process umask to 0117 around each bind and then puts the old one
  // back, from RouDi's thread and from the hub's own runtime at once: interleaved, the
  // two left /tmp/roudi 0640 in about 1 start in 10, and members were refused. With the
  // hub's umask already 0117, every such change is a no-op.
  umask(0117);
  const bool made_in_group = gid != own_gid && setegid(gid) == 0;
  double pool_mib = 0.0;
  // A fatal error while RouDi starts would abort with its shared memory left in /dev/shm.
  g_starting_group = group;
  std::optional<iox::cxx::GenericRAII> starting = iox::ErrorHandler::setTemporaryErrorHandler(
      [](const iox::Error error, const std::function<void()>, const iox::ErrorLevel level) {
        if (level != iox::ErrorLevel::FATAL) return;
        std::fprintf(stderr, "afhub hub: RouDi could not start (%s); removed its shared memory\n",
                     iox::ErrorHandler::toString(error));
        remove_shared_memory(g_starting_group);
        _exit(1);
      });
  iox::roudi::IceOryxRouDiComponents components(roudi_config(options.mempools, group, pool_mib));
  AfhubRouDi roudi(components.rouDiMemoryManager, components.portManager);
  {
    iox::runtime::PoshRuntimeSingleProcess runtime(kHubRuntimeName);
    starting.reset();
    if (gid != own_gid && !made_in_group && !open_to_group(gid)) return 1;
    // The members' teleops take their devices' claims there.
    if (gid != own_gid) claims_directory(own_hub_directory(), gid);
    std::fprintf(stderr,
                 "afhub hub: running (pid %d, %zu payload mempools, %.1f MiB, group '%s'). Ctrl-C "
                 "stops it.\n",
                 static_cast<int>(getpid()), options.mempools.size(), pool_mib, group.c_str());
    serve_until_stopped(roudi, *components.rouDiMemoryManager.portPool().value());
  }
  roudi.stop();
  remove_shared_memory(group);
  std::fprintf(stderr, "afhub hub: stopped\n");
  std::fflush(nullptr);
  // Clients still attached publish until they see the hub gone, each publish inside
  // its port's lock: RouDi's destructor would take the ports apart under them, and
  // abort on a lock a client holds (pthread_mutex_destroy: EBUSY). Their memory is
  // unlinked; the process ends without taking it apart. The lock goes first: an exiting
  // process's memory is unmapped before its files are closed, and `afhub hub stop`, a
  // new hub and the clients wait for the lock, not for that (a loaded CI machine took
  // over 5 s between SIGTERM and the lock's release).
  close(lock.fd);
  _exit(0);
}

// Whether `pid` runs the afhub executable: a last check before signalling it.
bool is_afhub_process(pid_t pid) {
  std::ifstream comm("/proc/" + std::to_string(pid) + "/comm");
  std::string name;
  return std::getline(comm, name) && name == "afhub";
}

int stop_hub(bool force) {
  const std::optional<HubIdentity> hub = running_hub();
  if (!hub) {
    std::fprintf(stderr, "afhub hub stop: no hub is running\n");
    return 0;
  }
  // The pid is the kernel's holder of the hub's lock, never a number read from a file.
  const std::optional<pid_t> pid = hub->pid > 0 ? std::optional<pid_t>(hub->pid) : std::nullopt;
  if (!pid || !is_afhub_process(*pid)) {
    std::fprintf(stderr,
                 "afhub hub stop: the hub's lock is held by %s; not signalling it. Stop the hub "
                 "where it runs (Ctrl-C, or `afhub hub stop` in its pid namespace).\n",
                 pid ? ("pid " + std::to_string(*pid) + ", which is not afhub").c_str()
                     : "a process in a pid namespace this one cannot see");
    return 1;
  }
  if (const auto attached = attached_processes(); !attached.empty()) {
    std::fprintf(stderr, "afhub hub stop: %zu process%s attached to the hub (pid %d):\n",
                 attached.size(), attached.size() == 1 ? " is" : "es are", *pid);
    for (const AttachedProcess& process : attached)
      std::fprintf(stderr, "  %s (pid %d)\n", process.name.c_str(), static_cast<int>(process.pid));
    if (!force) {
      std::fprintf(stderr,
                   "They would lose the hub until a new one starts. Stop them first, or stop the "
                   "hub anyway with `afhub hub stop --force`.\n");
      return 1;
    }
  }
  if (kill(*pid, SIGTERM) != 0) {
    std::fprintf(stderr, "afhub hub stop: cannot signal the hub (pid %d): %s\n", *pid,
                 std::strerror(errno));
    return 1;
  }
  auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(15);
  while (running_hub_pid()) {
    if (std::chrono::steady_clock::now() > deadline) {
      std::fprintf(stderr,
                   "afhub hub stop: the hub (pid %d) did not stop within 15 s (a stopped "
                   "process takes SIGTERM only once it runs on: `kill -CONT %d`)\n",
                   *pid, *pid);
      return 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::fprintf(stderr, "afhub hub stop: stopped the hub (pid %d)\n", *pid);
  return 0;
}

}  // namespace afhub
