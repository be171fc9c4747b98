// Starting programs with posix_spawn (see process_spawn.hpp).
#include "afhub/rt/process_spawn.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <thread>

#include "afhub/rt/safe_open.hpp"
#include "afhub/shm_layout/error.hpp"

namespace afhub {
namespace {

// posix_spawn's attributes and file actions, released however the spawn ends.
struct SpawnSetup {
  posix_spawnattr_t attributes;
  posix_spawn_file_actions_t actions;
  SpawnSetup() {
    posix_spawnattr_init(&attributes);
    posix_spawn_file_actions_init(&actions);
  }
  ~SpawnSetup() {
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attributes);
  }
  SpawnSetup(const SpawnSetup&) = delete;
  SpawnSetup& operator=(const SpawnSetup&) = delete;
};

// A descriptor of this process's, closed however the spawn ends.
struct Descriptor {
  int fd = -1;
  Descriptor() = default;
  ~Descriptor() {
    if (fd >= 0) close(fd);
  }
  Descriptor(const Descriptor&) = delete;
  Descriptor& operator=(const Descriptor&) = delete;
};

void redirect(posix_spawn_file_actions_t& actions, int from, int to) {
  if (from >= 0) posix_spawn_file_actions_adddup2(&actions, from, to);
}

}  // namespace

pid_t spawn_process(const std::vector<std::string>& argv, const SpawnOptions& options) {
  if (argv.empty() || argv.front().empty()) throw Error("spawn_process: no program to start");
  SpawnSetup setup;
  // Nothing of this process's signal handling goes across: a signal it ignores or
  // blocks (in the calling thread) would otherwise stay so in the child.
  sigset_t signals;
  sigemptyset(&signals);
  posix_spawnattr_setsigmask(&setup.attributes, &signals);
  sigfillset(&signals);
  posix_spawnattr_setsigdefault(&setup.attributes, &signals);
  short flags = POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF;
  if (options.detached) flags |= POSIX_SPAWN_SETSID;
  if (options.own_process_group) flags |= POSIX_SPAWN_SETPGROUP;  // group 0: its own pid
  posix_spawnattr_setflags(&setup.attributes, flags);

  posix_spawn_file_actions_t& actions = setup.actions;
  if ((options.detached || options.null_stdin) && options.stdin_fd < 0)
    posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  redirect(actions, options.stdin_fd, STDIN_FILENO);
  redirect(actions, options.stdout_fd, STDOUT_FILENO);
  redirect(actions, options.stderr_fd, STDERR_FILENO);
  // Output files are often in /tmp under predictable names: opened here, where a symlink,
  // a FIFO or another user's file planted at the name is refused (the child's own open
  // would follow, block or write into it).
  Descriptor output;
  if (!options.output_path.empty()) {
    output.fd =
        options.output_path == "/dev/null"
            ? open("/dev/null", O_WRONLY | O_CLOEXEC)
            : open_own_file(options.output_path, O_WRONLY | O_CREAT | O_TRUNC | O_NONBLOCK, 0644);
    if (output.fd < 0)
      throw Error("cannot start " + argv.front() + ": its output file " + options.output_path +
                  (errno == EPERM || errno == ELOOP || errno == ENXIO
                       ? " is not a regular file of this user's (a symlink, a FIFO or another "
                         "user's file is in its place): remove it, or pick another path"
                       : std::string(": ") + std::strerror(errno)));
    fcntl(output.fd, F_SETFL, fcntl(output.fd, F_GETFL) & ~O_NONBLOCK);
    posix_spawn_file_actions_adddup2(&actions, output.fd, STDOUT_FILENO);
    posix_spawn_file_actions_adddup2(&actions, output.fd, STDERR_FILENO);
  }
  if (options.close_other_descriptors) posix_spawn_file_actions_addclosefrom_np(&actions, 3);

  std::vector<char*> arguments;
  for (const std::string& argument : argv) arguments.push_back(const_cast<char*>(argument.c_str()));
  arguments.push_back(nullptr);
  std::vector<char*> environment;
  for (char** entry = environ; *entry; ++entry) environment.push_back(*entry);
  for (const std::string& entry : options.extra_environment)
    environment.push_back(const_cast<char*>(entry.c_str()));
  environment.push_back(nullptr);
  pid_t pid = -1;
  const int error = (options.search_path ? posix_spawnp : posix_spawn)(
      &pid, arguments.front(), &actions, &setup.attributes, arguments.data(), environment.data());
  if (error != 0)
    throw Error("cannot start " + argv.front() +
                (options.output_path.empty() ? "" : " with its output to " + options.output_path) +
                ": " + std::strerror(error) +
                (options.search_path && argv.front().find('/') == std::string::npos
                     ? " (looked for it on PATH)"
                     : ""));
  if (options.detached) std::thread([pid] { waitpid(pid, nullptr, 0); }).detach();
  return pid;
}

std::string this_executable() {
  char path[4096];
  const ssize_t n = readlink("/proc/self/exe", path, sizeof path - 1);
  if (n <= 0) throw Error("cannot find this executable through /proc/self/exe");
  return std::string(path, static_cast<std::size_t>(n));
}

}  // namespace afhub
