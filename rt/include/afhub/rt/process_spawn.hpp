// Starting another program without fork(): posix_spawn (vfork-like, nothing of this
// process runs in the child but the exec), so that a process with iceoryx's threads
// never runs code, nor allocates, in a forked copy of itself. The only way afhub and
// its tests start programs.
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace afhub {

struct SpawnOptions {
  // The child's standard streams: a descriptor of this process to put there (it may
  // be O_CLOEXEC), or -1 to share this process's.
  int stdin_fd = -1;
  int stdout_fd = -1;
  int stderr_fd = -1;
  // When not empty, stdout and stderr go to this file instead (created, truncated). A
  // symlink, a FIFO or another user's file at the path is refused (afhub::Error).
  std::string output_path;
  // stdin from /dev/null (as a detached child's always is).
  bool null_stdin = false;
  // Only the standard streams go across: every other descriptor of this process (its
  // shared memory, a socket not opened O_CLOEXEC) is closed in the child.
  bool close_other_descriptors = false;
  // Set in the child's environment beside this process's ("NAME=value" each).
  std::vector<std::string> extra_environment;
  // argv[0] found on PATH when it holds no '/' (as execvp).
  bool search_path = false;
  // In a process group of its own (its pid), so that one kill(-pid) reaches it and the
  // processes it starts.
  bool own_process_group = false;
  // Detached: in a session of its own (POSIX_SPAWN_SETSID: no controlling terminal,
  // no Ctrl-C from this one), stdin from /dev/null unless stdin_fd says otherwise,
  // and never waited for by the caller: a thread of this process reaps it when it
  // ends, so that it leaves no zombie however long it outlives its work for us.
  bool detached = false;
};

// Starts `argv` (argv[0]: the program) with default signal handling and an empty
// signal mask, and returns its pid; unless detached, the caller waits for it
// (waitpid). Throws afhub::Error naming the program when it cannot be started.
pid_t spawn_process(const std::vector<std::string>& argv, const SpawnOptions& options = {});

// This program's path (/proc/self/exe), to start another of its subcommands.
std::string this_executable();

}  // namespace afhub
