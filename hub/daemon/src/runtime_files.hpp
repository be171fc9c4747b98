// The files an iceoryx runtime keeps in /tmp: its socket /tmp/<name> and its lock
// /tmp/<name>.lock, locked (flock) for as long as the process lives. The lock tells
// which processes are attached without asking iceoryx; a lock nobody holds is what a
// killed process left behind.
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace afhub {

struct AttachedProcess {
  std::string name;  // its iceoryx runtime name, e.g. "afhub-ctl-1234"
  pid_t pid = 0;     // the holder of its lock, in the hub's pid namespace; 0 when unseen
};

// Whether the runtime `name`, registered with `pid`, is gone: its lock is free. True in
// any pid namespace, unlike a pid: the kernel frees a flock when its holder dies. When
// its lock file is missing (removed by hand or by a tmp cleaner), by `pid` (0: not known,
// and then not gone).
bool runtime_is_gone(const std::string& name, pid_t pid);

// Whether the runtime `name`, registered with `pid` (its own getpid()), runs in the
// hub's pid namespace: its lock's holder is that same pid here.
bool runtime_in_hub_pid_namespace(const std::string& name, pid_t pid);

// The same for an afhub client ("afhub-<role>-<pid>", named with its own getpid())
// that RouDi's introspection does not list yet: false for any other runtime.
bool client_in_hub_pid_namespace(const std::string& name);

// Every afhub runtime attached to the hub now, but the hub's own; sorted by name.
std::vector<AttachedProcess> attached_processes();

// Removes the socket and lock of every afhub runtime that is gone (its pid is gone,
// its lock is free and more than 2 s old); returns their names.
std::vector<std::string> remove_stale_runtime_files();

}  // namespace afhub
