// What machine a bench result came from: CPU, cores, memory, kernel, OS, date.
#include <sys/sysinfo.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <ctime>
#include <fstream>

#include "afhub/bench/bench.hpp"

namespace afhub::bench {
namespace {

// The value of the first "key<sep>value" line of a file, unquoted.
std::string field_of(const char* path, const std::string& key, char separator) {
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    if (line.compare(0, key.size(), key) != 0) continue;
    const auto at = line.find(separator);
    if (at == std::string::npos) continue;
    std::string value = line.substr(at + 1);
    value.erase(0, value.find_first_not_of(" \t\""));
    while (!value.empty() && (value.back() == '"' || value.back() == ' ')) value.pop_back();
    return value;
  }
  return "unknown";
}

}  // namespace

MachineInfo read_machine_info() {
  MachineInfo info;
  info.cpu = field_of("/proc/cpuinfo", "model name", ':');
  info.os = field_of("/etc/os-release", "PRETTY_NAME", '=');
  info.cores = static_cast<unsigned>(sysconf(_SC_NPROCESSORS_ONLN));
  utsname names{};
  if (uname(&names) == 0) info.kernel = names.release;
  struct sysinfo memory {};
  if (sysinfo(&memory) == 0)
    info.memory_gib = static_cast<double>(memory.totalram) * memory.mem_unit / (1u << 30);
  char date[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  info.date = date;
  return info;
}

}  // namespace afhub::bench
