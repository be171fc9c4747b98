// Input files checked before parsing (see input_file.hpp).
#include "afhub/yaml/input_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "afhub/shm_layout/error.hpp"

namespace afhub::yaml {
namespace {

[[noreturn]] void refuse(const std::string& path, const std::string& what) {
  throw Error(path + ": error: " + what);
}

std::string megabytes(std::uintmax_t bytes) {
  return std::to_string(bytes / (1u << 20)) + " MB";
}

// An open descriptor, closed however the reading ends.
struct Descriptor {
  int fd = -1;
  ~Descriptor() {
    if (fd >= 0) ::close(fd);
  }
};

// Opens `path` for reading and checks what it is; returns its size.
std::uintmax_t open_checked(const std::string& path, std::uintmax_t max_bytes,
                            const std::string& what, Descriptor& file) {
  file.fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (file.fd < 0) {
    const int error = errno;
    if (error == ENOENT) refuse(path, "no such file; expected " + what);
    if (error == EACCES)
      refuse(path, "permission denied: you cannot read this file; ask its owner for read access");
    refuse(path, std::string("cannot open it: ") + std::strerror(error));
  }
  struct stat status {};
  if (::fstat(file.fd, &status) != 0)
    refuse(path, std::string("cannot stat: ") + std::strerror(errno));
  if (S_ISDIR(status.st_mode)) refuse(path, "this is a directory; expected " + what);
  if (!S_ISREG(status.st_mode)) refuse(path, "this is not a regular file; expected " + what);
  const auto size = static_cast<std::uintmax_t>(status.st_size);
  if (size > max_bytes)
    refuse(path, "the file is " + megabytes(size) + ", larger than the " + megabytes(max_bytes) +
                     " afhub reads for " + what + "; is it the right file?");
  return size;
}

}  // namespace

std::uintmax_t check_input_file(const std::string& path, std::uintmax_t max_bytes,
                                const std::string& what) {
  Descriptor file;
  return open_checked(path, max_bytes, what, file);
}

std::string read_input_file(const std::string& path, std::uintmax_t max_bytes,
                            const std::string& what) {
  Descriptor file;
  const std::uintmax_t size = open_checked(path, max_bytes, what, file);
  // Read to the end, which may lie past the size a file gives (0 for /proc's, or one
  // growing while read): within the bound.
  std::string text(static_cast<std::size_t>(size) + 1, '\0');
  std::size_t done = 0;
  for (;;) {
    if (done == text.size()) {
      if (done > max_bytes)
        refuse(path, "the file holds more than the " + megabytes(max_bytes) + " afhub reads for " +
                         what + "; is it the right file?");
      text.resize(static_cast<std::size_t>(
          std::min<std::uintmax_t>(max_bytes + 1, std::uintmax_t{text.size()} * 2 + 4096)));
    }
    const ssize_t got = ::read(file.fd, text.data() + done, text.size() - done);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) refuse(path, std::string("cannot read it: ") + std::strerror(errno));
    if (got == 0) break;
    done += static_cast<std::size_t>(got);
  }
  text.resize(done);
  return text;
}

}  // namespace afhub::yaml
