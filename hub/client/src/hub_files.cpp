// The hub's files (see hub_files.hpp).
#include "afhub/hub/hub_files.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>

#include "afhub/shm_layout/error.hpp"

namespace afhub {
namespace {

constexpr const char* kRootDirectory = "/run/afhub";

std::string default_directory() {
  if (geteuid() == 0) return kRootDirectory;
  if (const char* runtime = std::getenv("XDG_RUNTIME_DIR"); runtime && *runtime)
    return std::string(runtime) + "/afhub";
  return "/tmp/afhub-" + std::to_string(geteuid());
}

// A directory that is ours: a real directory, owned by this user, writable by no one else.
void check_own_directory(const std::string& directory) {
  struct stat info {};
  if (lstat(directory.c_str(), &info) != 0)
    throw Error("cannot inspect the hub's directory " + directory + ": " + std::strerror(errno));
  const char* problem = nullptr;
  if (!S_ISDIR(info.st_mode))
    problem = "is not a directory (a symlink or a file planted there?)";
  else if (info.st_uid != geteuid())
    problem = "belongs to another user";
  else if (info.st_mode & (S_IWGRP | S_IWOTH))
    problem = "is writable by other users";
  if (problem)
    throw Error("the hub's directory " + directory + " " + problem +
                "; afhub will not use it. Remove it (as its owner or root) and try again.");
}

}  // namespace

std::string own_hub_directory() {
  const std::string directory = default_directory();
  const mode_t mode = geteuid() == 0 ? 0755 : 0700;
  if (mkdir(directory.c_str(), mode) != 0 && errno != EEXIST)
    throw Error("cannot create the hub's directory " + directory + ": " + std::strerror(errno));
  check_own_directory(directory);
  return directory;
}

std::string hub_directory() {
  if (geteuid() != 0 && flock_held(hub_lock_path(kRootDirectory))) return kRootDirectory;
  return own_hub_directory();
}

std::string hub_lock_path(const std::string& directory) {
  return directory + "/hub.lock";
}

std::string hub_identity_path(const std::string& directory) {
  return directory + "/hub.id";
}

std::string hub_log_path(const std::string& directory) {
  return directory + "/hub.log";
}

void claim_runtime_lock_file(const std::string& path) {
  for (int attempt = 0; attempt < 3; ++attempt) {
    const int fd = open(path.c_str(), O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC | O_WRONLY, 0600);
    if (fd >= 0) {
      close(fd);
      return;
    }
    if (errno != EEXIST)
      throw Error("cannot create iceoryx's lock file " + path + ": " + std::strerror(errno));
    struct stat info {};
    if (lstat(path.c_str(), &info) != 0) continue;  // gone meanwhile: create it again
    // Left by an earlier process of this user with the same pid: iceoryx takes it over.
    if (S_ISREG(info.st_mode) && info.st_uid == geteuid() && info.st_nlink == 1) return;
    const char* what = S_ISLNK(info.st_mode)   ? "a symlink"
                       : S_ISDIR(info.st_mode) ? "a directory"
                       : S_ISREG(info.st_mode) ? "a file"
                                               : "a special file";
    const std::string found = what + std::string(" owned by uid ") + std::to_string(info.st_uid);
    if (unlink(path.c_str()) != 0 && rmdir(path.c_str()) != 0)
      throw Error(path + " is " + found + ", where this process's iceoryx lock file goes, and " +
                  "it cannot be removed (" + std::strerror(errno) + "): remove it, or ask its " +
                  "owner to");
    std::fprintf(stderr, "afhub: removed %s: %s, where this process's iceoryx lock file goes\n",
                 path.c_str(), found.c_str());
  }
  throw Error("cannot create iceoryx's lock file " + path + ": something keeps replacing it");
}

std::optional<pid_t> flock_holder(const std::string& path) {
  struct stat info {};
  if (stat(path.c_str(), &info) != 0) return std::nullopt;
  // "1: FLOCK  ADVISORY  WRITE 1234 fe:00:10953343 0 EOF"; the kernel lists only the
  // locks of processes this one's pid namespace can see, with their pids here.
  char device_inode[64];
  std::snprintf(device_inode, sizeof device_inode, "%02x:%02x:%llu", major(info.st_dev),
                minor(info.st_dev), static_cast<unsigned long long>(info.st_ino));
  std::ifstream locks("/proc/locks");
  std::string line;
  while (std::getline(locks, line)) {
    if (line.find(" FLOCK ") == std::string::npos || line.find("->") != std::string::npos)
      continue;  // not a flock, or a process waiting for one
    const auto at = line.find(std::string(" ") + device_inode + " ");
    if (at == std::string::npos) continue;
    const auto pid_start = line.rfind(' ', at - 1);
    if (pid_start == std::string::npos) continue;
    const long pid = std::strtol(line.c_str() + pid_start + 1, nullptr, 10);
    if (pid > 0) return static_cast<pid_t>(pid);
  }
  return std::nullopt;
}

bool flock_held(const std::string& path) {
  const int fd = open_regular_file(path);
  if (fd < 0) return errno != ENOENT && flock_holder(path).has_value();
  const bool held = flock(fd, LOCK_SH | LOCK_NB) != 0 && errno == EWOULDBLOCK;
  close(fd);
  return held;
}

}  // namespace afhub
