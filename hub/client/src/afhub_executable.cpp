// Finding the afhub executable (see afhub_executable.hpp). Never a path fixed at build
// time: the build tree may be gone, and an install may have been moved.
#include "afhub_executable.hpp"

#include <unistd.h>

#include <cstdlib>
#include <string_view>
#include <vector>

#include "afhub/shm_layout/error.hpp"

namespace afhub {

std::string afhub_executable() {
  if (const char* env = std::getenv("AFHUB_EXECUTABLE"); env && *env) return env;
  std::vector<std::string> candidates;
  char self[4096];
  if (const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1); n > 0) {
    std::string dir(self, static_cast<std::size_t>(n));
    candidates.push_back(dir.substr(0, dir.rfind('/') + 1) + "afhub");
  }
  if (const char* path = std::getenv("PATH")) {
    std::string_view rest(path);
    while (!rest.empty()) {
      const auto colon = rest.find(':');
      const std::string_view dir = rest.substr(0, colon);
      if (!dir.empty()) candidates.push_back(std::string(dir) + "/afhub");
      rest = colon == std::string_view::npos ? std::string_view{} : rest.substr(colon + 1);
    }
  }
  for (const std::string& candidate : candidates)
    if (access(candidate.c_str(), X_OK) == 0) return candidate;
  throw Error(
      "no hub is running, and no `afhub` executable was found to start one (looked beside this "
      "program and on PATH). Start a hub with `afhub hub`, put afhub on PATH, or set "
      "AFHUB_EXECUTABLE to its path.");
}

}  // namespace afhub
