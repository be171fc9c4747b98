// Liveness by /proc (see liveness.hpp).
#include "liveness.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace afhub {

bool task_is_gone(pid_t id) {
  char path[32];
  std::snprintf(path, sizeof path, "/proc/%d/stat", static_cast<int>(id));
  std::FILE* file = std::fopen(path, "r");
  if (!file) return errno == ENOENT || errno == ESRCH;
  char stat[512];
  const std::size_t length = std::fread(stat, 1, sizeof stat - 1, file);
  std::fclose(file);
  stat[length] = '\0';
  // "id (name) S ...": the state follows the last ')' (a name may hold one).
  const char* name_end = std::strrchr(stat, ')');
  if (!name_end || name_end[1] != ' ') return false;
  return name_end[2] == 'Z' || name_end[2] == 'X';
}

}  // namespace afhub
