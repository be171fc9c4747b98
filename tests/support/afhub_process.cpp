// Running afhub from tests (see afhub_process.hpp).
#include "afhub_process.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "afhub/rt/process_spawn.hpp"
#include "afhub/shm_layout/error.hpp"

namespace afhub::test {
namespace {

int exit_code_of(int status) {
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

}  // namespace

std::string afhub_executable() {
  return AFHUB_TEST_EXECUTABLE;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

RunResult run_afhub(const std::vector<std::string>& args, std::chrono::milliseconds timeout) {
  std::vector<std::string> argv = {afhub_executable()};
  argv.insert(argv.end(), args.begin(), args.end());
  return run_command(argv, timeout);
}

int exit_code_if_ended(pid_t pid) {
  int status = 0;
  if (waitpid(pid, &status, WNOHANG) != pid) return -1;
  return exit_code_of(status);
}

RunResult run_command(const std::vector<std::string>& args, std::chrono::milliseconds timeout) {
  int out_pipe[2], err_pipe[2];
  if (pipe2(out_pipe, O_CLOEXEC) != 0 || pipe2(err_pipe, O_CLOEXEC) != 0)
    throw std::runtime_error("pipe failed");
  auto start = std::chrono::steady_clock::now();
  SpawnOptions options;
  options.search_path = true;
  options.stdout_fd = out_pipe[1];
  options.stderr_fd = err_pipe[1];
  pid_t pid = -1;
  try {
    pid = spawn_process(args, options);
  } catch (const Error& error) {
    for (int fd : {out_pipe[0], out_pipe[1], err_pipe[0], err_pipe[1]}) close(fd);
    RunResult result;
    result.exit_code = 127;  // as a shell says it
    result.err = error.what();
    return result;
  }
  close(out_pipe[1]);
  close(err_pipe[1]);
  RunResult result;
  pollfd fds[2] = {{out_pipe[0], POLLIN, 0}, {err_pipe[0], POLLIN, 0}};
  int open_streams = 2;
  auto deadline = start + timeout;
  bool timed_out = false;
  while (open_streams > 0) {
    auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      timed_out = true;
      kill(pid, SIGKILL);
      break;
    }
    if (poll(fds, 2, static_cast<int>(left.count())) <= 0) continue;
    for (int i = 0; i < 2; ++i) {
      if (fds[i].fd < 0 || !(fds[i].revents & (POLLIN | POLLHUP))) continue;
      char buffer[4096];
      ssize_t n = read(fds[i].fd, buffer, sizeof buffer);
      if (n <= 0) {
        close(fds[i].fd);
        fds[i].fd = -1;
        --open_streams;
      } else {
        (i == 0 ? result.out : result.err).append(buffer, static_cast<std::size_t>(n));
      }
    }
  }
  for (auto& fd : fds)
    if (fd.fd >= 0) close(fd.fd);
  int status = 0;
  waitpid(pid, &status, 0);
  result.exit_code = timed_out ? -1 : exit_code_of(status);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

pid_t spawn_afhub(const std::vector<std::string>& args, const std::string& log_path) {
  return spawn_wrapped_afhub({}, args, log_path);
}

pid_t spawn_command(const std::vector<std::string>& argv) {
  SpawnOptions options;
  options.search_path = true;
  return spawn_process(argv, options);
}

pid_t spawn_wrapped_afhub(const std::vector<std::string>& wrapper,
                          const std::vector<std::string>& args, const std::string& log_path) {
  std::vector<std::string> argv = wrapper;
  argv.push_back(afhub_executable());
  argv.insert(argv.end(), args.begin(), args.end());
  SpawnOptions options;
  options.search_path = true;
  options.output_path = log_path;
  return spawn_process(argv, options);
}

namespace {

// What each thread of a process that would not stop is doing, from /proc: its name,
// where the kernel holds it (wchan) and its system call (number and arguments).
std::string threads_of(pid_t pid) {
  std::string out;
  const std::string task = "/proc/" + std::to_string(pid) + "/task";
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(task, error)) {
    auto line = [&](const char* file) {
      std::string text = read_file((entry.path() / file).string());
      while (!text.empty() && (text.back() == '\n' || text.back() == '\0')) text.pop_back();
      return text;
    };
    out += "  thread " + entry.path().filename().string() + " (" + line("comm") + "): wchan " +
           line("wchan") + ", syscall " + line("syscall") + "\n";
  }
  return out;
}

}  // namespace

int stop_process(pid_t pid, int signal, std::chrono::milliseconds timeout) {
  kill(pid, signal);
  int status = 0;
  bool exited = wait_until([&] { return waitpid(pid, &status, WNOHANG) == pid; }, timeout);
  if (!exited) {
    // Said before the kill: a process that ignores its stop is a bug to find.
    std::fprintf(stderr, "stop_process: pid %d did not exit within %lld ms of signal %d:\n%s",
                 static_cast<int>(pid), static_cast<long long>(timeout.count()), signal,
                 threads_of(pid).c_str());
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
  }
  return exit_code_of(status);
}

int ScopedProcess::stop(int signal, std::chrono::milliseconds timeout) {
  if (pid <= 0) return 0;
  int code = stop_process(pid, signal, timeout);
  pid = -1;
  return code;
}

std::vector<std::string> stop_leftover_children() {
  std::vector<std::string> left;
  std::vector<pid_t> children;
  for (const auto& entry : std::filesystem::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    // /proc/PID/stat: "pid (command) state ppid ..."; the command may hold spaces.
    const std::string stat = read_file(entry.path().string() + "/stat");
    const std::size_t close = stat.rfind(')');
    if (close == std::string::npos) continue;
    char state = 0;
    int parent = 0;
    if (std::sscanf(stat.c_str() + close + 1, " %c %d", &state, &parent) != 2) continue;
    if (parent != getpid() || state == 'Z') continue;
    std::string command = read_file(entry.path().string() + "/cmdline");
    for (char& c : command) c = c ? c : ' ';
    left.push_back(name + ": " + command);
    children.push_back(std::stoi(name));
  }
  for (pid_t child : children) stop_process(child, SIGTERM);
  return left;
}

int occurrences(const std::string& text, const std::string& part) {
  int count = 0;
  for (std::size_t at = text.find(part); at != std::string::npos; at = text.find(part, at + 1))
    ++count;
  return count;
}

std::vector<double> numbers_after(const std::string& text, const std::string& key,
                                  std::size_t from) {
  std::vector<double> numbers;
  const std::size_t at = text.find(key, from);
  if (at == std::string::npos) return numbers;
  const char* cursor = text.c_str() + at + key.size();
  while (*cursor && *cursor != ']') {
    char* end = nullptr;
    numbers.push_back(std::strtod(cursor, &end));
    if (end == cursor) break;
    cursor = *end == ',' ? end + 1 : end;
  }
  return numbers;
}

std::string stack_traces(const std::string& pattern) {
  const RunResult pids = run_command({"pgrep", "-f", pattern});
  std::string out;
  std::istringstream in(pids.out);
  for (std::string pid; in >> pid;) {
    const RunResult gdb = run_command({"gdb", "-p", pid, "-batch", "-ex", "thread apply all bt"},
                                      std::chrono::seconds(60));
    out += "== stacks of pid " + pid + " (" + pattern + ")\n" + gdb.out + gdb.err;
  }
  return out.empty() ? "no process matches '" + pattern + "'\n" : out;
}

int wait_for_exit(ScopedProcess& process, std::chrono::milliseconds timeout) {
  int status = 0;
  if (!wait_until([&] { return waitpid(process.pid, &status, WNOHANG) == process.pid; }, timeout))
    return -1;
  process.pid = -1;
  return exit_code_of(status);
}

}  // namespace afhub::test
