// Why a path is not a regular file (see path_kind.hpp).
#include "path_kind.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace afhub::physics {

std::string not_a_regular_file(const std::filesystem::path& path) {
  struct stat info {};
  if (stat(path.c_str(), &info) != 0) {
    const int error = errno;
    if (error == ELOOP) return "is a symlink loop";
    if (error == ENOENT) {
      char target[4096];
      const ssize_t length = readlink(path.c_str(), target, sizeof target - 1);
      if (length >= 0) return "is a broken symlink to '" + std::string(target, length) + "'";
      return "does not exist";
    }
    if (error == ENAMETOOLONG) return "is a name too long for the file system";
    return std::string("cannot be read: ") + std::strerror(error);
  }
  if (S_ISREG(info.st_mode)) return "";
  if (S_ISDIR(info.st_mode)) return "is a directory";
  if (S_ISFIFO(info.st_mode)) return "is a FIFO";
  if (S_ISCHR(info.st_mode)) return "is a character device";
  if (S_ISBLK(info.st_mode)) return "is a block device";
  if (S_ISSOCK(info.st_mode)) return "is a socket";
  return "is not a regular file";
}

}  // namespace afhub::physics
