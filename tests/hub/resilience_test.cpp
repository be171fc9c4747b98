// A client killed with SIGKILL at random points, 50 times in a row, while another
// client reads and writes continuously: the hub and the other client keep
// working, each restart reattaches within 2 s, and no shared-memory chunk leaks
// beyond what iceoryx 2.0.3 itself cannot prevent (see kIceoryxKillWindowChunks).
// And the rare kill that lands inside publish(), made certain: a client that dies
// holding iceoryx's port locks does not wedge the hub.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <random>
#include <stop_token>
#include <string>
#include <thread>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/shm_layout/health.hpp"
#include "afhub_process.hpp"
#include "hub_environment.hpp"
#include "strict_json.hpp"

namespace afhub::test {
namespace {

using namespace std::chrono_literals;

std::int64_t now_ns();

// iceoryx 2.0.3 moves a chunk from a subscriber's queue into its used-chunk list
// (and back out on release) in two non-atomic steps: a process killed between them
// takes one reference with it that RouDi never returns (chunk_receiver.inl, tryGet).
// The window is some tens of nanoseconds per take; over 50 kills of a 1 kHz reader
// it is hit in about one run of a hundred. A leak per kill or per reattach (the
// bug this test is for) would show as 10 to 50 chunks, far above this allowance.
constexpr std::uint32_t kIceoryxKillWindowChunks = 2;

// True when `after` holds at most `allowance` more chunks than `before`, summed over
// the pools that hold more. A pool holding fewer is no leak: `before` may have caught
// a sample in flight (a fresh CI run saw one pool at 2 chunks before, 1 after).
bool within_allowance(const std::vector<std::uint32_t>& before,
                      const std::vector<std::uint32_t>& after, std::uint32_t allowance) {
  if (after.size() != before.size()) return false;
  std::uint32_t extra = 0;
  for (std::size_t i = 0; i < before.size(); ++i)
    if (after[i] > before[i]) extra += after[i] - before[i];
  return extra <= allowance;
}

// Used chunks of every pool in the payload segment, from the first health sample
// published after `after_ns` (empty when none comes).
std::vector<std::uint32_t> payload_chunks_in_use(LatestReader<Health>& health,
                                                 std::int64_t after_ns) {
  const Health* sample = nullptr;
  wait_until(
      [&] {
        sample = health.latest();
        return sample && sample->header.publish_stamp_ns > after_ns && sample->mempool_count > 0;
      },
      3s);
  std::vector<std::uint32_t> used;
  if (!sample || sample->header.publish_stamp_ns <= after_ns) return used;
  for (std::uint32_t i = 0; i < sample->mempool_count; ++i)
    if (sample->mempools[i].segment_id != sample->mempools[0].segment_id)
      used.push_back(sample->mempools[i].used_chunks);
  return used;
}

// The usage once two consecutive health samples agree: RouDi takes its mempool
// snapshot on its own clock, so one sample may predate the chunks of the last.
std::vector<std::uint32_t> settled_chunks_in_use(LatestReader<Health>& health) {
  std::vector<std::uint32_t> previous = payload_chunks_in_use(health, now_ns());
  for (int attempt = 0; attempt < 5; ++attempt) {
    std::vector<std::uint32_t> current = payload_chunks_in_use(health, now_ns());
    if (current == previous) return current;
    previous = current;
  }
  return previous;
}

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// The last `bytes` of a text: a failure message quotes a log without flooding.
std::string tail(const std::string& text, std::size_t bytes = 3000) {
  return text.size() <= bytes ? text : "..." + text.substr(text.size() - bytes);
}

// The client that keeps working: reads body1's state and commands its joints.
struct SteadyClient {
  std::atomic<std::uint64_t> fresh_states{0};
  std::atomic<std::int64_t> longest_gap_ns{0};
  double last_joint0 = 0.0;

  void run(std::stop_token stop) {
    BodyClient body("synth/body1");
    std::uint64_t last_sequence = 0;
    std::int64_t last_fresh = now_ns();
    while (!stop.stop_requested()) {
      const BodyState* state = body.latest_state();
      const std::int64_t now = now_ns();
      if (state && state->header.sequence != last_sequence) {
        last_sequence = state->header.sequence;
        last_joint0 = state->joints[0].position;
        ++fresh_states;
        if (now - last_fresh > longest_gap_ns) longest_gap_ns = now - last_fresh;
        last_fresh = now;
      }
      if (BodyCommand* command = body.loan_command(kMaxJointsPerBody)) {
        command->joint_count = 1;
        command->joints[0].type = JointCommandType::kPosition;
        command->joints[0].value = 0.4;
        body.publish_command(command);
      }
      std::this_thread::sleep_for(500us);
    }
  }
};

// A client that dies holding iceoryx's port locks, as one killed inside publish()
// does (hub/src/port_lock_repair.hpp), `linger` seconds after it connected. Without
// the hub's repair synth blocks on its next state publish, and RouDi on the cleanup
// after the dead client, so `ls` can no longer even register. Only child processes
// here: this process's iceoryx runtime belongs to the next test's hub.
void expect_hub_survives_client_dead_holding_port_locks(const char* linger) {
  ScopedProcess hub(start_test_hub());
  ASSERT_GT(hub.pid, 0);
  ScopedProcess synth = spawn_afhub({"synth", "--bodies", "1", "--joints", "1", "--no-autostart"},
                                    "/tmp/afhub-test-synth.log");
  ASSERT_TRUE(wait_until(
      [] {
        return run_afhub({"echo", "synth/body0", "-n", "1"}).exit_code == 0;
      },
      30s));

  const pid_t holder = spawn_command({AFHUB_PORT_LOCK_HOLDER, linger});
  int status = 0;
  waitpid(holder, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL)
      << "port_lock_holder did not die holding the locks (exit " << WEXITSTATUS(status) << ")";

  // RouDi notices the death after 1.5 s without keep-alives and cleans up; from
  // then on the hub serves new clients, and synth publishes again (over 500 Hz: its
  // loop skips the periods it was late for, so a busy machine takes some of its 1 kHz;
  // one blocked on the dead client's lock publishes nothing).
  std::this_thread::sleep_for(2s);
  RunResult ls;
  const bool served = wait_until(
      [&] {
        ls = run_afhub({"ls", "--json"}, 3s);
        if (ls.exit_code != 0) return false;
        const nlohmann::json bodies = parse_json(ls.out);
        const nlohmann::json* body = find_element(bodies, "body", "synth/body0");
        return body && body->at("rate_hz").is_number() &&  // null until measured
               body->at("rate_hz").get<double>() > 500.0;
      },
      10s);
  const std::string hub_log = read_file("/tmp/afhub-test-hub.log");
  EXPECT_TRUE(served) << "after a client died holding port locks: `afhub ls` exit " << ls.exit_code
                      << ", out: " << ls.out << "\nerr: " << tail(ls.err) << "\nThe hub's log:\n"
                      << tail(hub_log);
  EXPECT_TRUE(contains(hub_log, "died holding a publisher lock")) << tail(hub_log);
  EXPECT_TRUE(contains(hub_log, "died holding a subscriber queue lock")) << tail(hub_log);

  EXPECT_EQ(synth.stop(), 0);
  EXPECT_EQ(hub.stop(), 0);
}

// Dead before the hub listed it: RouDi's keep-alive monitor removes it, blocking on
// the locks until the hub's loop releases them.
TEST(Resilience, ClientDeadHoldingPortLocksAtOnceDoesNotWedgeTheHub) {
  expect_hub_survives_client_dead_holding_port_locks("0");
}

// Dead after the hub listed it: the hub's own loop sees it gone and has RouDi remove
// it, which takes the dead client's publisher lock; the loop must release the locks
// first, or it waits on them forever (the physics killed mid-publish under a bridge).
TEST(Resilience, ListedClientDeadHoldingPortLocksDoesNotWedgeTheHub) {
  expect_hub_survives_client_dead_holding_port_locks("3");
}

TEST(Resilience, KilledClientRestartsWhileOthersKeepWorking) {
  ScopedProcess hub(start_test_hub());
  ASSERT_GT(hub.pid, 0);
  connect_to_hub("resilience", HubPolicy::kRequire);
  LatestReader<Health> health({"afhub", "hub", "health"});
  const std::vector<std::uint32_t> before = settled_chunks_in_use(health);
  ASSERT_FALSE(before.empty());

  ScopedProcess synth = spawn_afhub({"synth", "--bodies", "2", "--joints", "2", "--no-autostart"},
                                    "/tmp/afhub-test-synth.log");
  ASSERT_TRUE(wait_until(
      [] {
        return run_afhub({"echo", "synth/body1", "-n", "1"}).exit_code == 0;
      },
      30s));

  SteadyClient steady;
  // A jthread: a failed assertion below still stops and joins it.
  std::jthread steady_thread([&](std::stop_token stop) { steady.run(stop); });

  std::mt19937 random(12345);
  double slowest_reattach_s = 0.0;
  {
    // Sees which client's commands arrive; gone before the chunks are counted again.
    LatestReader<BodyCommand> commands(body_command_channel("synth/body0"));
    for (int round = 0; round < 50; ++round) {
      const auto spawned = std::chrono::steady_clock::now();
      const std::uint64_t fresh_at_start = steady.fresh_states;
      // Scoped: a failed assertion must not leave it running (cmd re-attaches to
      // whatever hub comes next, which would be the next test's).
      const std::string client_log = "/tmp/afhub-test-client.log";
      ScopedProcess client = spawn_afhub(
          {"cmd", "synth/body0", "--joint-pos", "0.2,0.1", "--repeat", "1000"}, client_log);
      if (round % 5 == 4) {
        // Killed while it registers with the hub or opens its channels.
        std::this_thread::sleep_for(std::chrono::milliseconds(random() % 30));
      } else {
        // Killed mid-stream, after its commands arrive.
        bool attached = wait_until(
            [&] {
              const BodyCommand* command = commands.latest();
              return command &&
                     command->header.publisher_pid == static_cast<std::uint32_t>(client.pid);
            },
            30s);
        ASSERT_TRUE(attached)
            << "round " << round
            << ": the restarted client's commands did not arrive in 30 s. Its log:\n"
            << tail(read_file(client_log)) << "\nThe hub's log:\n"
            << tail(read_file("/tmp/afhub-test-hub.log"));
        slowest_reattach_s = std::max(
            slowest_reattach_s,
            std::chrono::duration<double>(std::chrono::steady_clock::now() - spawned).count());
        std::this_thread::sleep_for(std::chrono::milliseconds(random() % 100));
      }
      client.stop(SIGKILL);
      // The other client gets fresh states through every round: counted, not timed
      // (the wait only bounds a stall of the state stream).
      ASSERT_TRUE(wait_until([&] { return steady.fresh_states > fresh_at_start; }, 5s))
          << "round " << round << ": the steady client went without fresh state";
    }
  }
  std::printf("slowest reattach: %.3f s\n", slowest_reattach_s);
  std::printf("the steady client's longest wait for fresh state: %.3f s\n",
              static_cast<double>(steady.longest_gap_ns.load()) * 1e-9);

  // The other client kept getting fresh states, and its commands kept arriving.
  const std::uint64_t fresh_before = steady.fresh_states;
  EXPECT_TRUE(wait_until([&] { return steady.fresh_states > fresh_before; }, 5s))
      << "the steady client went without fresh state";
  steady_thread.request_stop();
  steady_thread.join();
  EXPECT_NEAR(steady.last_joint0, 0.4, 1e-3) << "the steady client's commands stopped arriving";

  // The hub still answers.
  RunResult ls = run_afhub({"ls"});
  EXPECT_EQ(ls.exit_code, 0) << tail(ls.err) << "\nThe hub's log:\n"
                             << tail(read_file("/tmp/afhub-test-hub.log"));
  EXPECT_NE(ls.out.find("synth/body0"), std::string::npos) << ls.out;

  // Everything stops; once RouDi has cleaned up after the killed clients, the
  // payload pools hold what they held before the first client started.
  EXPECT_EQ(synth.stop(), 0);
  std::vector<std::uint32_t> after;
  const bool exact = wait_until(
      [&] {
        after = settled_chunks_in_use(health);
        return after == before;
      },
      15s);
  const bool settled = exact || within_allowance(before, after, kIceoryxKillWindowChunks);
  std::string before_text, after_text;
  for (auto used : before) before_text += std::to_string(used) + " ";
  for (auto used : after) after_text += std::to_string(used) + " ";
  std::printf("chunks in use per payload pool: before [%s] after [%s]\n", before_text.c_str(),
              after_text.c_str());
  if (settled && !exact)
    std::printf(
        "the pools differ from before within the allowance: a kill inside iceoryx's "
        "take/release window (see kIceoryxKillWindowChunks), or a sample in flight before\n");
  EXPECT_TRUE(settled) << "chunks leaked: before [" << before_text << "] after [" << after_text
                       << "]";

  EXPECT_EQ(hub.stop(), 0);
}

}  // namespace
}  // namespace afhub::test
