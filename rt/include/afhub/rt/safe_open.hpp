// Opening files in directories that other users can write (/tmp), where a symlink,
// a FIFO or another user's file may be planted at a predictable name.
#pragma once

#include <sys/types.h>

#include <string>

namespace afhub {

// Opens `path` with `flags` | O_NOFOLLOW | O_CLOEXEC, refusing a file that belongs to
// another user than this process's (or root's), or that is not a regular file. Returns
// -1 with errno set (EPERM: refused). A FIFO is refused without waiting for its other
// end only when `flags` holds O_NONBLOCK.
int open_own_file(const std::string& path, int flags, mode_t mode = 0600);

// Opens `path` for reading only if it is a regular file: with O_NOFOLLOW, and with
// O_NONBLOCK, so that a FIFO swapped in by another user cannot hang the caller (a plain
// open of a FIFO waits for a writer). Returns -1 with errno set (EINVAL: not a regular file).
int open_regular_file(const std::string& path);

}  // namespace afhub
