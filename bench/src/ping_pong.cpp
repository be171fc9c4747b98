// The ping-pong between the bench and one peer process per transport. Rounds are
// interleaved (every round visits every size, and every transport for each size)
// so that drift of the machine's load hits every transport alike.
#include <netinet/in.h>
#include <sched.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <utility>

#include "afhub/bench/bench.hpp"
#include "afhub/rt/process_spawn.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "child_process.hpp"
#include "transport.hpp"

namespace afhub::bench {
namespace {

constexpr std::int64_t kAnswerTimeoutNs = 10'000'000'000;
constexpr std::int64_t kConnectTimeoutNs = 20'000'000'000;
constexpr std::int64_t kPeerLookNs = 100'000'000;

// Pins the calling thread to `cpu`, or lets it run anywhere again (-1). Best
// effort: an unpinned run is still a valid run.
void pin_to_cpu(int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  for (long i = 0; i < sysconf(_SC_NPROCESSORS_ONLN); ++i)
    if (cpu < 0 || i == cpu) CPU_SET(i, &set);
  sched_setaffinity(0, sizeof set, &set);
}

// Two busy-polling ends get a CPU each when there are two.
int ping_cpu() {
  return sysconf(_SC_NPROCESSORS_ONLN) >= 2 ? 0 : -1;
}
int pong_cpu() {
  return sysconf(_SC_NPROCESSORS_ONLN) >= 2 ? 1 : -1;
}

struct Peer {
  TransportResult* result;
  TransportKind kind;
  std::unique_ptr<Transport> end;
  std::unique_ptr<ChildProcess> process;
  std::string log;  // what the peer process says
};

// The peer did not answer: when it has ended, what it said (its log is kept).
[[noreturn]] void fail_silent(Peer& peer, const std::string& what) {
  std::string message =
      std::string(transport_name(peer.kind)) + ": the peer did not answer " + what;
  if (!peer.process->running()) {
    const std::string said = first_line_with(peer.log, "error");
    message += said.empty() ? "; it exited (see " + peer.log + ")" : "; it exited: " + said;
  }
  throw Error(message);
}

// Sends ping `round` and waits for its pong, dropping stale ones. Looks every 100 ms
// whether the peer still runs.
Message exchange(Peer& peer, std::uint32_t bytes, std::uint64_t round, std::int64_t& sent_ns) {
  sent_ns = peer.end->send(bytes, round, 0);
  for (std::int64_t look_ns = sent_ns + kPeerLookNs;; look_ns += kPeerLookNs) {
    std::optional<Message> pong = peer.end->receive(look_ns);
    if (pong && pong->round == round) return *pong;
    if (stop_requested()) throw Error("stopped");
    if (pong) continue;
    if (!peer.process->running()) fail_silent(peer, "a " + std::to_string(bytes) + " byte ping");
    if (look_ns - sent_ns >= kAnswerTimeoutNs)
      fail_silent(peer, "a " + std::to_string(bytes) + " byte ping within 10 s");
  }
}

// Pings until the peer answers: subscriptions and discovery take their time.
void handshake(Peer& peer, std::uint64_t& round) {
  const std::int64_t give_up = monotonic_ns() + kConnectTimeoutNs;
  for (;;) {
    const std::uint64_t asked = ++round;
    peer.end->send(kMinPayloadBytes, asked, 0);
    for (std::int64_t until = monotonic_ns() + 100'000'000; monotonic_ns() < until;)
      if (auto pong = peer.end->receive(until); pong && pong->round == asked) return;
    if (stop_requested()) throw Error("interrupted");
    if (!peer.process->running()) fail_silent(peer, "its first pings");
    if (monotonic_ns() > give_up) fail_silent(peer, "in 20 s");
  }
}

// A free TCP port on loopback for our own rosmaster.
int free_port() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof address;
  bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address);
  getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  close(fd);
  return ntohs(address.sin_port);
}

// A folder of this run's own, removed with what is in it when the run ends.
struct OwnFolder {
  std::string path;
  ~OwnFolder() {
    std::error_code ignored;
    if (!path.empty()) std::filesystem::remove_all(path, ignored);
  }
};

}  // namespace

void run_ping_pong(const BenchOptions& options, BenchResults& results) {
  install_stop_signal_handlers();
  const std::string session = std::to_string(getpid());
  OwnFolder ros_home;  // declared first: removed after rosmaster has stopped
  std::unique_ptr<ChildProcess> rosmaster;
  std::vector<Peer> peers;
  std::vector<std::string> peer_logs;  // one per peer started
  for (const std::string& name : options.transports)
    if (!parse_transport(name))
      throw Error("unknown transport '" + name +
                  "': choose from afhub, afhub-slot, shm-floor, dds, dds-shm, uds, ros1");
  results.transports.reserve(options.transports.size());
  for (const std::string& name : options.transports) {
    const std::optional<TransportKind> kind = parse_transport(name);
    TransportResult& result = results.transports.emplace_back();
    result.name = name;
    result.skipped = transport_unavailable(*kind);
    if (!result.skipped.empty()) {
      std::fprintf(stderr, "afhub bench: skipping %s: %s\n", name.c_str(), result.skipped.c_str());
      continue;
    }
    if (*kind == TransportKind::kRos1 && !rosmaster) {
      const std::string port = std::to_string(free_port());
      setenv("ROS_MASTER_URI", ("http://127.0.0.1:" + port + "/").c_str(), 1);
      setenv("ROS_IP", "127.0.0.1", 1);
      // Its logs, wherever HOME is: in a folder of this run's own (a fixed name in /tmp
      // could be a symlink planted by another user).
      char folder[] = "/tmp/afhub-bench-ros-XXXXXX";
      if (!mkdtemp(folder)) throw Error("cannot make a folder for rosmaster's logs in /tmp");
      ros_home.path = folder;
      setenv("ROS_HOME", folder, 1);
      rosmaster = std::make_unique<ChildProcess>(
          std::vector<std::string>{"rosmaster", "--core", "-p", port});
    }
    std::unique_ptr<Transport> end;
    try {
      end = open_transport(*kind, Side::kPing, session, options.touch);
    } catch (const Error& error) {
      // Cyclone DDS built without its iceoryx transport: a row this machine cannot have.
      if (*kind != TransportKind::kDdsShm) throw;
      result.skipped = error.what();
      std::fprintf(stderr, "afhub bench: skipping %s: %s\n", name.c_str(), error.what());
      continue;
    }
    std::fprintf(stderr, "afhub bench: starting the %s peer\n", name.c_str());
    Peer peer{&result, *kind, std::move(end), nullptr,
              "/tmp/afhub-bench-" + session + "-" + name + ".log"};
    std::vector<std::string> peer_args{
        this_executable(), "bench", "--peer",     name,
        "--session",       session, "--peer-cpu", std::to_string(pong_cpu())};
    if (options.touch) peer_args.push_back("--touch");
    peer_logs.push_back(peer.log);
    peer.process = std::make_unique<ChildProcess>(peer_args, peer.log);
    peer.end->connect(monotonic_ns() + kConnectTimeoutNs);
    peers.push_back(std::move(peer));
  }
  pin_to_cpu(ping_cpu());

  std::uint64_t round_id = 0;
  for (Peer& peer : peers) handshake(peer, round_id);
  std::int64_t sent_ns = 0;
  for (std::uint32_t bytes : kPayloadSizes)
    for (Peer& peer : peers)
      for (std::uint32_t i = 0; i < options.warmup_pings; ++i)
        exchange(peer, bytes, ++round_id, sent_ns);

  for (std::uint32_t round = 1; round <= options.rounds; ++round) {
    if (stop_requested()) throw Error("interrupted");
    std::fprintf(stderr, "afhub bench: latency round %u of %u\n", round, options.rounds);
    for (std::uint32_t bytes : kPayloadSizes) {
      for (Peer& peer : peers) {
        auto& one_way = peer.result->one_way_us[bytes];
        auto& round_trip = peer.result->round_trip_us[bytes];
        for (std::uint32_t i = 0; i < options.pings_per_round; ++i) {
          const Message pong = exchange(peer, bytes, ++round_id, sent_ns);
          one_way.push_back(static_cast<double>(pong.peer_receive_ns - sent_ns) * 1e-3);
          one_way.push_back(static_cast<double>(pong.receive_ns - pong.send_ns) * 1e-3);
          round_trip.push_back(static_cast<double>(pong.receive_ns - sent_ns) * 1e-3);
        }
      }
    }
  }
  pin_to_cpu(-1);
  // Kept only when the run failed: what a peer said is then the reason.
  for (const std::string& log : peer_logs) std::filesystem::remove(log);
}

int run_peer(const std::string& transport, const std::string& session, int cpu, bool touch) {
  install_stop_signal_handlers();
  const std::optional<TransportKind> kind = parse_transport(transport);
  if (!kind) throw Error("unknown transport '" + transport + "'");
  std::unique_ptr<Transport> end = open_transport(*kind, Side::kPong, session, touch);
  end->connect(monotonic_ns() + kConnectTimeoutNs);
  pin_to_cpu(cpu);
  while (!stop_requested())
    if (std::optional<Message> ping = end->receive(monotonic_ns() + 100'000'000))
      end->send(ping->bytes, ping->round, ping->receive_ns);
  return 0;
}

}  // namespace afhub::bench
