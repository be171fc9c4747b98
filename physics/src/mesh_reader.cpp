// Mesh files read in afhub-mesh-reader (see mesh_reader.hpp).
#include "mesh_reader.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string_view>

#include "afhub/physics/mesh.hpp"
#include "afhub/rt/process_spawn.hpp"
#include "afhub/shm_layout/error.hpp"
#include "mesh_wire.hpp"

namespace afhub::physics {
namespace {

using Clock = std::chrono::steady_clock;

// One reader process is given at most so many files (its command line stays short).
constexpr std::size_t kFilesPerReader = 256;
// What is kept of the reader's stderr (assimp's assertion message, when it aborts).
constexpr std::size_t kMaxDiagnosticBytes = 4096;

struct Descriptor {
  int fd = -1;
  Descriptor() = default;
  explicit Descriptor(int from) : fd(from) {}
  Descriptor(const Descriptor&) = delete;
  Descriptor& operator=(const Descriptor&) = delete;
  ~Descriptor() { reset(); }
  void reset() {
    if (fd >= 0) ::close(fd);
    fd = -1;
  }
};

struct Pipe {
  Descriptor read_end, write_end;
  Pipe() {
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0)
      throw Error(std::string("cannot read meshes: no pipe to a mesh reader: ") +
                  std::strerror(errno));
    read_end.fd = fds[0];
    write_end.fd = fds[1];
  }
};

bool executable(const std::string& path) {
  return ::access(path.c_str(), X_OK) == 0;
}

// Starts the reader on `files`, its stdout and stderr on the pipes' write ends, with
// nothing else of this process: no other descriptor (the hub's shared memory), the
// default signal handling, an empty signal mask.
pid_t start_reader(const std::string& program, const std::vector<std::string>& files, int out,
                   int err) {
  std::vector<std::string> argv{program};
  argv.insert(argv.end(), files.begin(), files.end());
  SpawnOptions options;
  options.stdout_fd = out;
  options.stderr_fd = err;
  options.null_stdin = true;
  options.close_other_descriptors = true;
  // Its heap on huge pages (glibc's tunable): a fresh process faulting in its memory a
  // page at a time is a fifth of what reading small meshes costs.
  if (!std::getenv("GLIBC_TUNABLES"))
    options.extra_environment.push_back("GLIBC_TUNABLES=glibc.malloc.hugetlb=1");
  try {
    return spawn_process(argv, options);
  } catch (const Error& error) {
    throw Error(std::string("cannot read meshes: ") + error.what());
  }
}

// The reader process, killed and reaped however the reading ends.
struct Reader {
  pid_t pid;
  Descriptor exited;  // a pidfd: readable once it ended
  int status = 0;
  bool reaped = false;
  explicit Reader(pid_t started)
      : pid(started), exited(static_cast<int>(::syscall(SYS_pidfd_open, started, 0))) {}
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;
  ~Reader() { stop(); }
  void stop() {
    if (reaped) return;
    ::kill(pid, SIGKILL);
    reap();
  }
  void reap() {
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    reaped = true;
  }
};

// Keeps the start of what the reader says on stderr.
void keep(std::string& diagnostics, const char* text, ssize_t bytes) {
  if (diagnostics.size() < kMaxDiagnosticBytes)
    diagnostics.append(
        text, std::min(static_cast<std::size_t>(bytes), kMaxDiagnosticBytes - diagnostics.size()));
}

// Reads what is left on the ended reader's stderr.
void drain(int fd, std::string& diagnostics) {
  if (fd < 0) return;
  ::fcntl(fd, F_SETFL, O_NONBLOCK);  // a process it started may hold it open
  char text[4096];
  for (ssize_t got; fd >= 0 && (got = ::read(fd, text, sizeof text)) != 0;)
    if (got > 0)
      keep(diagnostics, text, got);
    else if (errno != EINTR)
      break;
}

// Why the reader ended before its record for a file, as the end of "PATH: error: ...".
std::string why_it_ended(int status, const std::string& diagnostics) {
  std::string last_line;
  std::string_view rest(diagnostics);
  while (!rest.empty()) {
    const std::size_t end = rest.find('\n');
    const std::string_view line = rest.substr(0, end);
    if (line.find_first_not_of(" \t\r") != std::string_view::npos) last_line = line;
    rest = end == std::string_view::npos ? std::string_view{} : rest.substr(end + 1);
  }
  const std::string said = last_line.empty() ? "" : " (it said: " + last_line + ")";
  if (WIFSIGNALED(status) && WTERMSIG(status) == SIGXCPU)
    return "reading it took more than " + std::to_string(mesh_wire::kCpuSecondsPerMesh) +
           " s of CPU time, and was stopped; is it a mesh?";
  if (WIFSIGNALED(status))
    return std::string("the mesh reader (assimp) crashed on it: ") +
           ::sigabbrev_np(WTERMSIG(status)) + said +
           "; the file is malformed: repair or re-export it";
  if (WIFEXITED(status) && WEXITSTATUS(status) != 0)
    return "the mesh reader stopped with exit code " + std::to_string(WEXITSTATUS(status)) + said;
  return "the mesh reader ended without reading it" + said;
}

// The reader's stdout, record by record: where the next bytes go, and what a
// complete record says. Every header is checked before anything is allocated for it.
class Records {
 public:
  explicit Records(std::size_t count) : count_(count) {}
  char* where() {
    return header_done_ < sizeof header_ ? reinterpret_cast<char*>(&header_) + header_done_
                                         : body_.data() + body_done_;
  }
  std::size_t wanted() const {
    return header_done_ < sizeof header_ ? sizeof header_ - header_done_
                                         : body_.size() - body_done_;
  }
  // Takes `bytes` just written at where(); returns true when they complete a record,
  // then in `result`. Throws Error (a sentence) on a malformed record.
  bool take(std::size_t bytes, MeshReadResult& result) {
    if (header_done_ < sizeof header_) {
      header_done_ += bytes;
      if (header_done_ < sizeof header_) return false;
      body_.assign(body_bytes(), '\0');
      body_done_ = 0;
    } else {
      body_done_ += bytes;
    }
    if (body_done_ < body_.size()) return false;
    decode(result);
    header_done_ = 0;
    ++next_;
    return true;
  }
  std::size_t next() const { return next_; }

 private:
  std::size_t body_bytes() const {
    const mesh_wire::Header& h = header_;
    if (h.magic != mesh_wire::kMagic || h.index != next_ || next_ >= count_)
      throw Error("it wrote a record out of order");
    if (h.status == mesh_wire::kRefused && h.message_bytes <= mesh_wire::kMaxMessageBytes &&
        h.vertex_count == 0 && h.triangle_count == 0)
      return h.message_bytes;
    if (h.status == mesh_wire::kRead && h.message_bytes == 0 &&
        h.vertex_count <= kMaxMeshVertices && h.triangle_count <= kMaxMeshTriangles)
      return 3 * sizeof(float) * h.vertex_count + 3 * sizeof(std::uint32_t) * h.triangle_count;
    throw Error("it wrote a record with impossible counts");
  }
  void decode(MeshReadResult& result) const {
    if (header_.status == mesh_wire::kRefused) {
      result.error.assign(body_.begin(), body_.end());
      for (char& c : result.error)
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = ' ';
      if (result.error.empty()) result.error = "cannot read this mesh";
      return;
    }
    RawMesh& mesh = result.mesh;
    mesh.xyz.resize(3 * header_.vertex_count);
    mesh.triangles.resize(3 * header_.triangle_count);
    const std::size_t xyz_bytes = mesh.xyz.size() * sizeof(float);
    // (An empty mesh's vectors have no storage: memcpy must not see their null pointers.)
    if (!mesh.xyz.empty()) std::memcpy(mesh.xyz.data(), body_.data(), xyz_bytes);
    if (!mesh.triangles.empty())
      std::memcpy(mesh.triangles.data(), body_.data() + xyz_bytes,
                  mesh.triangles.size() * sizeof(std::uint32_t));
    for (std::uint32_t index : mesh.triangles)
      if (index >= header_.vertex_count) throw Error("it wrote a triangle naming no vertex");
  }

  std::size_t count_;
  std::size_t next_ = 0;
  mesh_wire::Header header_{};
  std::size_t header_done_ = 0;
  std::vector<char> body_;
  std::size_t body_done_ = 0;
};

// Runs one reader on `paths[from, to)`, filling their results; returns the first it
// has no result for (`to` when all were read). A file the reader died on, or was
// stopped on, gets the reason as its error and is passed over.
std::size_t read_some(const std::vector<std::string>& paths, std::size_t from, std::size_t to,
                      const std::string& program, std::chrono::milliseconds time_per_mesh,
                      std::vector<MeshReadResult>& results) {
  Pipe out, err;
  Reader reader(start_reader(program,
                             std::vector<std::string>(paths.begin() + from, paths.begin() + to),
                             out.write_end.fd, err.write_end.fd));
  out.write_end.reset();
  err.write_end.reset();
  Records records(to - from);
  std::string diagnostics;
  std::string reason;  // why reading stopped early
  auto deadline = Clock::now() + time_per_mesh;
  // Until the reader closes its stdout (it ended), then until it can be reaped.
  while (reason.empty() && !reader.reaped) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) {
      char seconds[32];
      std::snprintf(seconds, sizeof seconds, "%g", time_per_mesh.count() / 1000.0);
      reason = std::string("reading it took more than ") + seconds +
               " s, and was stopped; is it a mesh?";
      break;
    }
    pollfd watched[3] = {{out.read_end.fd, POLLIN, 0},
                         {err.read_end.fd, POLLIN, 0},
                         {out.read_end.fd < 0 ? reader.exited.fd : -1, POLLIN, 0}};
    if (::poll(watched, 3, static_cast<int>(std::min<long long>(left, 1000))) < 0) {
      if (errno == EINTR) continue;
      reason = std::string("cannot wait for the mesh reader: ") + std::strerror(errno);
      break;
    }
    if (watched[1].revents) {
      char text[4096];
      const ssize_t got = ::read(err.read_end.fd, text, sizeof text);
      if (got <= 0)
        err.read_end.reset();
      else
        keep(diagnostics, text, got);
    }
    if (watched[0].revents) {
      const ssize_t got = ::read(out.read_end.fd, records.where(), records.wanted());
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) {
        out.read_end.reset();  // it ended: wait for its status
        if (reader.exited.fd < 0) reader.reap();
        continue;
      }
      try {
        MeshReadResult result;
        if (records.take(static_cast<std::size_t>(got), result)) {
          const std::size_t file = from + records.next() - 1;
          if (!result.error.empty()) result.error = paths[file] + ": error: " + result.error;
          results[file] = std::move(result);
          deadline = Clock::now() + time_per_mesh;
        }
      } catch (const Error& error) {
        reason = std::string("the mesh reader failed: ") + error.what();
      }
    }
    if (watched[2].revents) reader.reap();
  }
  reader.stop();
  drain(err.read_end.fd, diagnostics);
  const std::size_t failed = from + records.next();
  if (failed == to) return to;
  if (reason.empty()) reason = why_it_ended(reader.status, diagnostics);
  results[failed].mesh = {};
  results[failed].error = paths[failed] + ": error: " + reason;
  return failed + 1;
}

}  // namespace

std::string mesh_reader_program() {
  static const char kName[] = "afhub-mesh-reader";
  if (const char* env = std::getenv("AFHUB_MESH_READER"); env && *env) return env;
  char self[4096];
  if (const ssize_t n = ::readlink("/proc/self/exe", self, sizeof self - 1); n > 0) {
    const std::string path(self, static_cast<std::size_t>(n));
    const std::string beside = path.substr(0, path.rfind('/') + 1) + kName;
    if (executable(beside)) return beside;
  }
  if (const char* path = std::getenv("PATH")) {
    std::string_view rest(path);
    while (!rest.empty()) {
      const auto colon = rest.find(':');
      const std::string_view dir = rest.substr(0, colon);
      const std::string candidate = std::string(dir) + "/" + kName;
      if (!dir.empty() && executable(candidate)) return candidate;
      rest = colon == std::string_view::npos ? std::string_view{} : rest.substr(colon + 1);
    }
  }
  throw Error(std::string("cannot read meshes: no `") + kName +
              "` beside this program or on PATH (it is installed with afhub); set "
              "AFHUB_MESH_READER to its path");
}

std::vector<MeshReadResult> read_mesh_files(const std::vector<std::string>& paths,
                                            const MeshReaderOptions& options) {
  std::vector<MeshReadResult> results(paths.size());
  if (paths.empty()) return results;
  const std::string program = options.program.empty() ? mesh_reader_program() : options.program;
  for (std::size_t next = 0; next < paths.size();)
    next = read_some(paths, next, std::min(paths.size(), next + kFilesPerReader), program,
                     options.time_per_mesh, results);
  return results;
}

}  // namespace afhub::physics
