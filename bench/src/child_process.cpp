// Child processes of the bench (see child_process.hpp).
#include "child_process.hpp"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>

#include "afhub/rt/process_spawn.hpp"

namespace afhub::bench {

ChildProcess::ChildProcess(const std::vector<std::string>& argv, const std::string& output_path) {
  // Through setpriv (util-linux), which sets the parent-death signal and then runs the
  // program in its place: posix_spawn has no attribute for it.
  std::vector<std::string> words{"setpriv", "--pdeathsig", "TERM", "--"};
  words.insert(words.end(), argv.begin(), argv.end());
  SpawnOptions options;
  options.search_path = true;
  options.output_path = output_path;
  pid_ = spawn_process(words, options);
}

int ChildProcess::wait(int timeout_ms) {
  if (pid_ < 0) return exit_code_;
  for (int waited = 0;; waited += 10) {
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      return exit_code_;
    }
    if (waited >= timeout_ms) return -1;
    usleep(10'000);
  }
}

bool ChildProcess::running() {
  return wait(0) == -1;
}

int ChildProcess::stop(int grace_ms) {
  if (pid_ < 0) return exit_code_;
  kill(pid_, SIGTERM);
  if (wait(grace_ms) != -1) return exit_code_;
  kill(pid_, SIGKILL);
  return wait(5000);
}

std::string first_line_with(const std::string& path, const std::string& text) {
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);)
    if (line.find(text) != std::string::npos) return line;
  return "";
}

}  // namespace afhub::bench
