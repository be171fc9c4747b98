// The hub's own files: its lock, its identity and its log, in a directory that only
// the hub's user can write. Never /tmp, where another user could plant a symlink or
// hold the lock.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <optional>
#include <string>

#include "afhub/rt/safe_open.hpp"  // open_own_file, open_regular_file

namespace afhub {

// The directory of this user's hub: /run/afhub for root, else $XDG_RUNTIME_DIR/afhub,
// else /tmp/afhub-<uid>. Created 0755 (root) or 0700 when missing; throws
// afhub::Error when it exists but is a symlink, belongs to another user, or is
// writable by others.
std::string own_hub_directory();

// The directory where a hub is looked for: root's /run/afhub when a hub runs there
// (a member of the hub's --group attaches to it), else own_hub_directory().
std::string hub_directory();

std::string hub_lock_path(const std::string& directory);      // flock'ed by the hub, 0600
std::string hub_identity_path(const std::string& directory);  // "<pid> <instance>", 0644
std::string hub_log_path(const std::string& directory);

// iceoryx's runtime opens /tmp/<runtime name>.lock with O_CREAT and follows a symlink
// there: one planted by another user (where fs.protected_symlinks is 0) would have this
// process create or lock a file of that user's choosing. So the file is made first,
// here, with O_EXCL and O_NOFOLLOW. Something else found at the path (a symlink, a
// directory, another user's file) is removed, and said on stderr; throws afhub::Error
// when it cannot be (this user may not remove it).
void claim_runtime_lock_file(const std::string& path);

// The pid, in this process's pid namespace, of the process holding a flock on `path`
// (from /proc/locks); nullopt when none is held, or the holder is in a pid namespace
// this process cannot see.
std::optional<pid_t> flock_holder(const std::string& path);

// Whether some process holds a flock on `path`, in any pid namespace: probed with a
// non-blocking shared lock when the file can be opened, else from /proc/locks.
bool flock_held(const std::string& path);

}  // namespace afhub
