// The hub daemon (see hub_daemon.hpp): one lock file, RouDi in this process, the
// catalog and health publishers, and a clean stop on SIGINT or SIGTERM.
#include "afhub/hub/hub_daemon.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <exception>
#include <set>
#include <string>
#include <thread>

#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/stop_signal.hpp"
#include "afhub_roudi.hpp"
#include "catalog_builder.hpp"
#include "health_reporter.hpp"
#include "iceoryx_hoofs/posix_wrapper/posix_access_rights.hpp"
#include "iceoryx_posh/iceoryx_posh_config.hpp"
#include "iceoryx_posh/roudi/iceoryx_roudi_components.hpp"
#include "iceoryx_posh/roudi/port_pool.hpp"
#include "iceoryx_posh/runtime/posh_runtime_single_process.hpp"
#include "liveness.hpp"
#include "port_lock_repair.hpp"
#include "runtime_files.hpp"

namespace afhub {
namespace {

iox::RouDiConfig_t roudi_config(const std::vector<MempoolSpec>& pools, double& total_mib) {
  iox::mepoo::MePooConfig mempools;
  total_mib = 0.0;
  for (const MempoolSpec& pool : pools) {
    mempools.addMemPool({pool.payload_bytes, pool.chunk_count});
    total_mib += static_cast<double>(pool.payload_bytes) * pool.chunk_count / (1024.0 * 1024.0);
  }
  iox::RouDiConfig_t config;
  auto group = iox::posix::PosixGroup::getGroupOfCurrentProcess().getName();
  config.m_sharedMemorySegments.push_back({group, group, mempools});
  return config;
}

// The hub lock, released last: after RouDi is gone, so that a new hub can start at once.
struct HubLock {
  int fd = -1;
  ~HubLock() {
    if (fd >= 0) close(fd);
  }
};

// Takes the hub lock and writes this pid in it; -1 when another hub has it.
int take_hub_lock() {
  int fd = open(hub_lock_path().c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) return -1;
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
  std::string pid = std::to_string(getpid()) + "\n";
  if (ftruncate(fd, 0) != 0 || write(fd, pid.data(), pid.size()) < 0) {
    close(fd);
    return -1;
  }
  return fd;
}

// Unregisters every process whose pid is gone (`removed`: those already asked for,
// which RouDi's introspection may list a moment longer).
void remove_dead_processes(AfhubRouDi& roudi, HealthReporter& health,
                           std::set<std::string>& removed) {
  std::set<std::string> listed;
  for (const auto& [name, pid] : health.registered_processes()) {
    listed.insert(name);
    if (pid <= 0 || pid == getpid() || removed.count(name) || !task_is_gone(pid)) continue;
    removed.insert(name);
    if (roudi.remove_process(name))
      std::fprintf(stderr, "afhub hub: %s (pid %d) is gone; removed its ports and chunks\n",
                   name.c_str(), static_cast<int>(pid));
  }
  std::erase_if(removed, [&](const std::string& name) { return !listed.count(name); });
}

void serve_until_stopped(AfhubRouDi& roudi, iox::roudi::PortPool& ports) {
  CatalogBuilder catalog;
  HealthReporter health;
  std::set<std::string> removed;
  bool catalog_failed = false;
  auto next_file_sweep = std::chrono::steady_clock::now();
  while (!stop_requested()) {
    auto now = std::chrono::steady_clock::now();
    release_port_locks_of_dead_threads(ports);
    remove_dead_processes(roudi, health, removed);
    if (now >= next_file_sweep) {
      for (const std::string& name : remove_stale_runtime_files())
        std::fprintf(stderr, "afhub hub: removed the files %s left in /tmp\n", name.c_str());
      next_file_sweep = now + std::chrono::seconds(1);
    }
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
    health.poll(now, catalog.body_count(), iox::MAX_PUBLISHERS - publishers);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

}  // namespace

int run_hub_daemon(const HubOptions& options) {
  HubLock lock{take_hub_lock()};
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
  install_stop_signal_handlers();
  quiet_iceoryx_logs();

  double pool_mib = 0.0;
  iox::roudi::IceOryxRouDiComponents components(roudi_config(options.mempools, pool_mib));
  AfhubRouDi roudi(components.rouDiMemoryManager, components.portManager);
  iox::runtime::PoshRuntimeSingleProcess runtime("afhub-hub");
  std::fprintf(stderr,
               "afhub hub: running (pid %d, %zu payload mempools, %.1f MiB). Ctrl-C stops it.\n",
               static_cast<int>(getpid()), options.mempools.size(), pool_mib);
  serve_until_stopped(roudi, *components.rouDiMemoryManager.portPool().value());
  std::fprintf(stderr, "afhub hub: stopped\n");
  return 0;
}

int stop_hub(bool force) {
  auto pid = running_hub_pid();
  if (!pid || *pid <= 0) {
    std::fprintf(stderr, "afhub hub stop: no hub is running\n");
    return 0;
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
  auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (running_hub_pid()) {
    if (std::chrono::steady_clock::now() > deadline) {
      std::fprintf(stderr, "afhub hub stop: the hub (pid %d) did not stop within 5 s\n", *pid);
      return 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::fprintf(stderr, "afhub hub stop: stopped the hub (pid %d)\n", *pid);
  return 0;
}

}  // namespace afhub
