// One writer per recording: `afhub record` and `afhub record --recover` each hold an
// exclusive flock on the file while they write it. Without it a second recorder on the
// same file truncated and interleaved the first's (both said they recorded, the file
// read as neither), and a recover under a live recorder replaced the file the recorder
// went on writing, unlinked.
#pragma once

#include <sys/file.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "afhub/shm_layout/error.hpp"

namespace afhub::mcap {

// Takes the lock on `fd`, open on `path`, or throws naming the file.
inline void lock_recording(int fd, const std::string& path) {
  if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return;
  if (errno == EWOULDBLOCK)
    throw Error(path +
                " is being written by another process (an `afhub record` or a "
                "recovery holds it): give another -o, or wait until that one ends");
  throw Error("cannot lock " + path + ": " + std::strerror(errno));
}

}  // namespace afhub::mcap
