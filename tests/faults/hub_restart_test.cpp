// The hub going away must not kill anyone. Under a running physics, two controllers
// and an echo, the hub is stopped (`afhub hub stop`) or SIGKILLed and a new one
// started, 10 times in a row: every process is still alive after each loss and comes
// back under each new hub (the catalog lists the arm again, both controllers' commands
// arrive, echo prints again), with the payload mempools' usage back at what it was under
// the first hub (no chunk leak).
// The re-attach times are printed, not asserted (docs/faults.md quotes them).
//
// `afhub view` is taken through a hub stop and a SIGKILL too: it tells its pages that
// the hub is lost, then serves live frames again.
//
// The test process never joins a hub itself: iceoryx's runtime could not join the next
// one. It looks through tests/faults/fault_probe, a process per look.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "afhub/hub/hub_presence.hpp"
#include "afhub/rt/process_spawn.hpp"
#include "afhub/shm_layout/body_command.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/health.hpp"
#include "afhub/shm_layout/world.hpp"
#include "afhub_process.hpp"
#include "hub_environment.hpp"
#include "web_client.hpp"

namespace afhub::test {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

constexpr int kRounds = 10;

std::int64_t ns_of(Clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}

std::string tail(const std::string& text, std::size_t bytes = 2500) {
  return text.size() <= bytes ? text : "..." + text.substr(text.size() - bytes);
}

std::size_t line_count(const std::string& path) {
  const std::string text = read_file(path);
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

struct Member {
  std::string name, log;
  pid_t pid = -1;
  int ended = -1;  // exit code once it ended
};

std::string median_text(std::vector<double> values) {
  if (values.empty()) return "none";
  std::sort(values.begin(), values.end());
  char text[96];
  std::snprintf(text, sizeof text, "min %.3f  median %.3f  max %.3f s (%zu)", values.front(),
                values[values.size() / 2], values.back(), values.size());
  return text;
}

// Starts tests/faults/fault_probe with `args`, its stdout and stderr in two files.
pid_t start_probe(const std::vector<std::string>& args, const std::string& out_path,
                  const std::string& err_path) {
  std::vector<std::string> argv{AFHUB_FAULT_PROBE};
  argv.insert(argv.end(), args.begin(), args.end());
  SpawnOptions options;
  options.stdout_fd = open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  options.stderr_fd = open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  const pid_t pid = spawn_process(argv, options);
  close(options.stdout_fd);
  close(options.stderr_fd);
  return pid;
}

// Runs tests/faults/fault_probe with `args`, at most `timeout`.
RunResult run_afhub_probe(const std::vector<std::string>& args,
                          std::chrono::milliseconds timeout = 20s) {
  const std::string out_path = "/tmp/afhub-fault-probe.out";
  const std::string err_path = "/tmp/afhub-fault-probe.err";
  const pid_t pid = start_probe(args, out_path, err_path);
  RunResult result;
  int status = 0;
  if (wait_until([&] { return waitpid(pid, &status, WNOHANG) == pid; }, timeout)) {
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  } else {
    kill(pid, SIGKILL);
    waitpid(pid, nullptr, 0);
  }
  result.out = read_file(out_path);
  result.err = read_file(err_path);
  return result;
}

// Chunks in use per payload pool (by its chunks' payload bytes), as the probe sees them
// (empty when it could not look).
using PoolUsage = std::map<std::uint32_t, std::uint32_t>;
// `why`: what the probe said when it read nothing (a failure then shows it).
PoolUsage chunks_in_use(std::string* why = nullptr) {
  PoolUsage usage;
  RunResult probe = run_afhub_probe({"chunks"});
  if (why) why->clear();
  if (probe.exit_code != 0) {
    if (why) *why = "exit " + std::to_string(probe.exit_code) + ": " + probe.err;
    return usage;
  }
  std::istringstream items(probe.out);
  for (std::string item; items >> item;) {
    const auto colon = item.find(':');
    usage[static_cast<std::uint32_t>(std::stoul(item.substr(0, colon)))] =
        static_cast<std::uint32_t>(std::stoul(item.substr(colon + 1)));
  }
  return usage;
}

std::string usage_text(const PoolUsage& usage) {
  std::string text;
  for (const auto& [bytes, used] : usage)
    text += std::to_string(bytes) + " B: " + std::to_string(used) + ", ";
  return text.empty() ? "(none)" : text.substr(0, text.size() - 2);
}

// The pool that holds payloads of `bytes`: the smallest that fits.
std::uint32_t pool_of(const PoolUsage& usage, std::size_t bytes) {
  for (const auto& [pool_bytes, used] : usage)
    if (pool_bytes >= bytes) return pool_bytes;
  return 0;
}

// Body states, commands and world states stream at 1 kHz: a health snapshot catches
// chunks in flight (a reader's previous sample, one being written, a sample queued for
// a reader the loaded machine has not run yet), up to about one per body channel (the
// arm has 16; seen: 11 over the first hub's count under CI's load). A leak per
// re-attach holds at least one chunk per channel every round, so it passes this bound
// by the second round; and once every client has stopped the check below is exact
// (but for the health samples in flight, below).
constexpr std::uint32_t kInFlightChunks = 16;

// The hub publishes its health with each count of the pools by RouDi (every 100 ms), and the
// probe reads that count through a health reader of its own: at a count, that reader may
// still hold the sample before the hub's newest, and until its next poll the one before
// that. So the health pool's count goes up and down by up to two from one look to the
// next, under every hub alike (seen: 3 under the first hub, then 2). The pool also holds
// the arm's scene description, loaned at its real size (8 bodies, 25680 B: just over the
// 25560 B tier), one chunk in the physics' history, and nothing else of the test's.
constexpr std::uint32_t kHealthInFlight = 2;

// Same usage as `baseline`: exactly in every pool but the streaming ones and the health
// pool; within `streaming` chunks over or under in the streaming ones; in the health
// pool, at most kHealthInFlight over (fewer is no leak: the baseline may have caught
// samples in flight). A leak of one health chunk per re-attach is r + 1 over by round r:
// past the bound by the third round, or the fifth when the baseline caught two in flight.
bool same_usage(const PoolUsage& baseline, const PoolUsage& usage, std::uint32_t streaming) {
  if (usage.size() != baseline.size() || usage.empty()) return false;
  // (Sent at their real size: the arm's states and commands, of 0 to 7 joints, are in
  // the tiers that hold 7.)
  const std::uint32_t streaming_pools[] = {pool_of(baseline, body_command_bytes(7)),
                                           pool_of(baseline, body_state_bytes(7)),
                                           pool_of(baseline, sizeof(WorldState))};
  const std::uint32_t health_pool = pool_of(baseline, sizeof(Health));
  long long streaming_difference = 0;
  for (const auto& [bytes, used] : baseline) {
    const auto found = usage.find(bytes);
    if (found == usage.end()) return false;
    const long long difference = static_cast<long long>(found->second) - used;
    if (bytes == health_pool) {
      if (difference > kHealthInFlight) return false;
    } else if (std::find(std::begin(streaming_pools), std::end(streaming_pools), bytes) !=
               std::end(streaming_pools)) {
      streaming_difference += difference;
    } else if (difference != 0) {
      return false;
    }
  }
  // Fewer is no leak (a physics not run for a while holds fewer in flight; seen: 17 fewer).
  return streaming_difference <= streaming;
}

class HubRestart : public ::testing::TestWithParam<bool> {};

TEST_P(HubRestart, EveryClientOutlivesTheHubAndReattaches) {
  const bool sigkill = GetParam();
  // Whatever happens below, the hub of the moment is stopped at the end.
  ScopedProcess hub(start_test_hub());
  ASSERT_GT(hub.pid, 0);

  // What the hub itself holds, before any client: what the last hub holds again once
  // every client has stopped. A new hub's first counts of its pools come a few seconds
  // after it answers on a loaded machine (a run beside a demo missed the probe's 3 s).
  PoolUsage empty;
  ASSERT_TRUE(wait_until(
      [&] {
        empty = chunks_in_use();
        return !empty.empty();
      },
      30s));

  const std::string model = std::string(AFHUB_EXAMPLE_MODELS) + "/arm7.yaml";
  ScopedProcess physics =
      spawn_afhub({"run", model, "--no-autostart"}, "/tmp/afhub-fault-physics.log");
  ASSERT_TRUE(wait_until(
      [] {
        return contains(run_afhub({"ls", "--json"}, 3s).out, "arm/link3");
      },
      15s))
      << tail(read_file("/tmp/afhub-fault-physics.log"));
  ScopedProcess hold = spawn_afhub({"ctl", "hold", "arm/base"}, "/tmp/afhub-fault-hold.log");
  ScopedProcess sine =
      spawn_afhub({"ctl", "sine", "arm/link3", "--amplitude", "0.2"}, "/tmp/afhub-fault-sine.log");
  ScopedProcess echo =
      spawn_afhub({"echo", "arm/base", "--rate", "20"}, "/tmp/afhub-fault-echo.log");
  std::vector<Member> members = {
      {"afhub run", "/tmp/afhub-fault-physics.log", physics.pid},
      {"afhub ctl hold", "/tmp/afhub-fault-hold.log", hold.pid},
      {"afhub ctl sine", "/tmp/afhub-fault-sine.log", sine.pid},
      {"afhub echo", "/tmp/afhub-fault-echo.log", echo.pid},
  };
  const std::vector<std::string> attached_args = {"attached", "10000",
                                                  "arm/base:" + std::to_string(hold.pid),
                                                  "arm/link3:" + std::to_string(sine.pid)};
  RunResult first = run_afhub_probe(attached_args, 20s);
  ASSERT_EQ(first.exit_code, 0) << first.out << first.err
                                << "\nhold: " << tail(read_file("/tmp/afhub-fault-hold.log"));
  ASSERT_TRUE(wait_until([] { return line_count("/tmp/afhub-fault-echo.log") > 2; }, 5s));
  // Looked at until a probe answers, as for `empty`: one probe failed on a loaded
  // machine (beside a demo and two other hub tests).
  PoolUsage baseline;
  ASSERT_TRUE(wait_until(
      [&] {
        baseline = chunks_in_use();
        return !baseline.empty();
      },
      30s));
  std::printf("payload chunks in use under the first hub: %s\n", usage_text(baseline).c_str());

  std::map<std::string, std::vector<double>> reattach_s;
  const auto all_alive = [&](int round, const char* when) {
    bool alive = true;
    for (Member& member : members) {
      if (member.ended < 0) member.ended = exit_code_if_ended(member.pid);
      if (member.ended >= 0) {
        ADD_FAILURE() << "round " << round << ", " << when << ": " << member.name << " (pid "
                      << member.pid << ") ended with exit code " << member.ended << ". Its log:\n"
                      << tail(read_file(member.log));
        alive = false;
      }
    }
    return alive;
  };

  for (int round = 0; round < kRounds; ++round) {
    // The loss.
    if (sigkill) {
      kill(hub.pid, SIGKILL);
      waitpid(hub.pid, nullptr, 0);
    } else {
      RunResult stop = run_afhub({"hub", "stop", "--force"});
      ASSERT_EQ(stop.exit_code, 0) << stop.err;
      waitpid(hub.pid, nullptr, 0);
    }
    hub.pid = -1;
    // Clients aborted within about 20 ms of the hub's stop before they outlived it.
    std::this_thread::sleep_for(500ms);
    ASSERT_TRUE(all_alive(round, "after the hub went away"));
    const std::size_t echo_lines = line_count("/tmp/afhub-fault-echo.log");

    // A new hub.
    hub.pid = spawn_afhub({"hub"}, "/tmp/afhub-test-hub.log");
    ASSERT_TRUE(wait_until(
        [] { return probe_roudi() == RoudiPresence::kRunning && running_hub_pid().has_value(); },
        kHubStartWait))
        << read_file("/tmp/afhub-test-hub.log");
    const Clock::time_point up = Clock::now();

    // Everyone back: the arm in the catalog, both controllers' commands, echo's lines.
    RunResult back = run_afhub_probe(attached_args, 20s);
    std::map<std::string, double> seconds;
    std::istringstream lines(back.out);
    for (std::string what, body; lines >> what >> body;) {
      long long stamp = 0;
      lines >> stamp;
      seconds[what + " " + body] = static_cast<double>(stamp - ns_of(up)) * 1e-9;
    }
    ASSERT_EQ(back.exit_code, 0) << "round " << round
                                 << ": not everyone came back.\nprobe: " << back.out << back.err
                                 << "\nphysics: " << tail(read_file("/tmp/afhub-fault-physics.log"))
                                 << "\nhold: " << tail(read_file("/tmp/afhub-fault-hold.log"))
                                 << "\nsine: " << tail(read_file("/tmp/afhub-fault-sine.log"));
    ASSERT_TRUE(
        wait_until([&] { return line_count("/tmp/afhub-fault-echo.log") > echo_lines + 1; }, 20s))
        << "round " << round << ": echo printed nothing under the new hub. Its log:\n"
        << tail(read_file("/tmp/afhub-fault-echo.log"));
    seconds["echo prints"] = std::chrono::duration<double>(Clock::now() - up).count();
    const double physics_s = seconds["catalog arm/base"];
    reattach_s["physics (arm in the catalog)"].push_back(physics_s);
    reattach_s["ctl hold (commands arrive)"].push_back(seconds["command arm/base"]);
    reattach_s["ctl sine (commands arrive)"].push_back(seconds["command arm/link3"]);
    reattach_s["echo (prints again)"].push_back(seconds["echo prints"]);
    std::printf("round %d (%s): physics %.3f s, ctl hold %.3f s, ctl sine %.3f s, echo %.3f s\n",
                round, sigkill ? "SIGKILL" : "hub stop", physics_s, seconds["command arm/base"],
                seconds["command arm/link3"], seconds["echo prints"]);
    std::fflush(stdout);
    ASSERT_TRUE(all_alive(round, "under the new hub"));

    // No chunk leak: the new hub's pools hold what the first one's did.
    PoolUsage used;
    std::string probe_said;
    const bool same = wait_until(
        [&] {
          used = chunks_in_use(&probe_said);
          return same_usage(baseline, used, kInFlightChunks);
        },
        15s);
    EXPECT_TRUE(same) << "round " << round << ": payload chunks in use " << usage_text(used)
                      << "; under the first hub " << usage_text(baseline)
                      << "; the probe: " << probe_said;
  }
  for (const auto& [what, values] : reattach_s)
    std::printf("re-attach after %s, %s: %s\n", sigkill ? "a hub SIGKILL" : "`afhub hub stop`",
                what.c_str(), median_text(values).c_str());

  // Everyone still stops cleanly on SIGTERM, and the last hub's pools then hold exactly
  // what an empty hub holds (but for health samples in flight).
  for (ScopedProcess* process : {&echo, &sine, &hold, &physics}) EXPECT_EQ(process->stop(), 0);
  PoolUsage after;
  const bool clean = wait_until(
      [&] {
        after = chunks_in_use();
        return same_usage(empty, after, 0);
      },
      15s);
  EXPECT_TRUE(clean) << "payload chunks in use once every client stopped: " << usage_text(after)
                     << "; with no client under the first hub: " << usage_text(empty);
}

// A process's make-safe hooks (a driver zeroing its force) run when the hub goes
// away, before the process re-executes, and again in the next image.
TEST(HubLoss, MakeSafeHooksRunBeforeTheReexec) {
  const std::string hub_log = "/tmp/afhub-test-hub.log", out = "/tmp/afhub-fault-hooked.out",
                    err = "/tmp/afhub-fault-hooked.err";
  // An earlier run's files would say "attached 0" and "hook ran" before this probe
  // writes a line.
  unlink(out.c_str());
  unlink(err.c_str());
  ScopedProcess hub = spawn_afhub({"hub"}, hub_log);
  ASSERT_TRUE(wait_until([] { return probe_roudi() == RoudiPresence::kRunning; }, kHubStartWait));
  ScopedProcess hooked = start_probe({"hooked"}, out, err);
  ASSERT_TRUE(wait_until([&] { return contains(read_file(out), "attached 0"); }, 10s))
      << read_file(err);
  EXPECT_FALSE(contains(read_file(err), "hook ran")) << "with the hub up; the probe said:\n"
                                                     << read_file(err) << "the hub said:\n"
                                                     << read_file(hub_log);

  for (int round = 1; round <= 2; ++round) {
    ASSERT_EQ(run_afhub({"hub", "stop", "--force"}).exit_code, 0);
    waitpid(hub.pid, nullptr, 0);
    // Both lines of this loss: the hook's alone may be read before the process's own (the
    // order check would then compare with the last loss's line).
    ASSERT_TRUE(wait_until(
        [&] {
          const std::string text = read_file(err);
          return occurrences(text, "hook ran") == round &&
                 occurrences(text, "outputs made safe") == round;
        },
        5s))
        << read_file(err);
    // The hook ran first, then the process said its outputs are safe and re-executed.
    const std::string text = read_file(err);
    EXPECT_LT(text.rfind("hook ran"), text.rfind("outputs made safe")) << text;
    hub.pid = spawn_afhub({"hub"}, hub_log);
    ASSERT_TRUE(wait_until(
        [&] { return contains(read_file(out), "attached " + std::to_string(round)); }, 10s))
        << read_file(err);
  }
  EXPECT_EQ(hooked.stop(), 0) << read_file(err);
  EXPECT_EQ(hub.stop(), 0);
}

// The flags and catalog count of a viewer frame (viewer/include/afhub/viewer/pose_feed.hpp).
std::uint32_t frame_word(const std::vector<std::uint8_t>& frame, std::size_t at) {
  std::uint32_t word = 0;
  if (frame.size() >= at + 4) std::memcpy(&word, frame.data() + at, 4);
  return word;
}
bool says_hub_lost(const std::vector<std::uint8_t>& frame) {
  return (frame_word(frame, 12) & 2) != 0;
}

// Live frames on `page`: the hub is not lost, bodies are listed, and the simulation
// time moves on from one frame to a later one.
bool live_frames(FrameCounter& page, std::chrono::milliseconds timeout) {
  double seen = -1.0;
  return wait_until(
      [&] {
        const std::vector<std::uint8_t> frame = page.last_frame();
        if (frame.size() < 32 || says_hub_lost(frame) || frame_word(frame, 24) == 0) return false;
        const double sim_time_s = page.last_sim_time_s();
        if (seen >= 0.0 && sim_time_s > seen) return true;
        seen = sim_time_s;
        return false;
      },
      timeout);
}

// `afhub view` outlives its hub like every client (before, it served its last frame as
// live forever). Meanwhile its pages are told the hub is lost; once a hub is back they
// get live frames again, on the same port.
// `afhub record` through a hub SIGKILL: the file it was writing ends complete (its
// summary and footer), and once a hub is back it records into the next file.
TEST(HubLoss, ARecordingEndsCompleteWhenTheHubGoesAndGoesOnIntoTheNextFile) {
  const std::string log = "/tmp/afhub-fault-record.log", file = "/tmp/afhub-fault-record.mcap",
                    next = "/tmp/afhub-fault-record.1.mcap";
  // An earlier run's files would pass for this run's before its recorder registered.
  for (const std::string& path : {log, file, next}) unlink(path.c_str());
  ScopedProcess hub(start_test_hub());
  ASSERT_GT(hub.pid, 0);
  ScopedProcess physics =
      spawn_afhub({"run", std::string(AFHUB_EXAMPLE_MODELS) + "/arm7.yaml", "--no-autostart"},
                  "/tmp/afhub-fault-record-physics.log");
  ScopedProcess recorder = spawn_afhub({"record", "-o", file}, log);
  // `afhub info` of a file as far as it reads: {complete, messages}.
  const auto info = [](const std::string& path) {
    const RunResult run = run_afhub({"info", path, "--json"});
    std::smatch complete, messages;
    const std::regex complete_key("\"complete\":(true|false)"),
        messages_key("\"messages\":([0-9]+)");
    if (run.exit_code != 0 || !std::regex_search(run.out, complete, complete_key) ||
        !std::regex_search(run.out, messages, messages_key))
      return std::make_pair(false, 0ull);
    return std::make_pair(complete[1] == "true", std::stoull(messages[1]));
  };
  ASSERT_TRUE(wait_until([&] { return info(file).second > 1000; }, 30s)) << read_file(log);

  kill(hub.pid, SIGKILL);
  waitpid(hub.pid, nullptr, 0);
  hub.pid = -1;
  ASSERT_TRUE(wait_until(
      [&] { return read_file(log).find("the hub is gone: ") != std::string::npos; }, 20s))
      << read_file(log);
  const auto [complete, messages] = info(file);
  EXPECT_TRUE(complete) << read_file(log);
  EXPECT_GT(messages, 1000u);

  hub.pid = spawn_afhub({"hub"}, "/tmp/afhub-test-hub.log");
  ASSERT_TRUE(wait_until([] { return probe_roudi() == RoudiPresence::kRunning; }, kHubStartWait));
  EXPECT_TRUE(wait_until([&] { return info(next).second > 1000; }, 60s)) << read_file(log);
  EXPECT_NE(read_file(log).find("waiting for a hub"), std::string::npos) << read_file(log);
  EXPECT_EQ(recorder.stop(SIGINT), 0) << read_file(log);
  EXPECT_TRUE(info(next).first) << read_file(log);
  EXPECT_EQ(physics.stop(), 0);

  // The recording played on a loop outlives its hub too (it ran on, writing into the
  // hub that was gone, and never came back).
  const std::string play_log = "/tmp/afhub-fault-play.log";
  ScopedProcess player = spawn_afhub({"play", file, "--loop"}, play_log);
  const auto played = [] { return contains(run_afhub({"ls"}, 5s).out, "afhub/arm/base"); };
  ASSERT_TRUE(wait_until(played, 30s)) << read_file(play_log);
  kill(hub.pid, SIGKILL);
  waitpid(hub.pid, nullptr, 0);
  hub.pid = spawn_afhub({"hub"}, "/tmp/afhub-test-hub.log");
  ASSERT_TRUE(wait_until([] { return probe_roudi() == RoudiPresence::kRunning; }, kHubStartWait));
  EXPECT_TRUE(wait_until(played, 60s)) << read_file(play_log);
  EXPECT_NE(read_file(play_log).find("waiting for a hub"), std::string::npos)
      << read_file(play_log);
  EXPECT_EQ(player.stop(SIGINT), 0) << read_file(play_log);
}

// `afhub record --duration` through a hub SIGKILL: the duration spans the files, from
// the first one's first message, the hub's absence included (each file took the whole
// duration again: 7.6 s recorded for --duration 4 across two kills); the recorder ends
// by itself.
TEST(HubLoss, ARecordingsDurationSpansTheFilesAcrossAHubRestart) {
  const std::string log = "/tmp/afhub-fault-duration.log", first = "/tmp/afhub-fault-duration.mcap",
                    second = "/tmp/afhub-fault-duration.1.mcap";
  for (const std::string& path : {log, first, second}) unlink(path.c_str());
  ScopedProcess hub(start_test_hub());
  ASSERT_GT(hub.pid, 0);
  ScopedProcess physics =
      spawn_afhub({"run", std::string(AFHUB_EXAMPLE_MODELS) + "/arm7.yaml", "--no-autostart"},
                  "/tmp/afhub-fault-duration-physics.log");
  constexpr double kDurationS = 8.0;
  ScopedProcess recorder = spawn_afhub({"record", "-o", first, "--duration", "8"}, log);
  // {first log time, last log time} of a file, from `afhub info` (0s when unreadable).
  const auto span = [](const std::string& path) {
    const RunResult run = run_afhub({"info", path, "--json"});
    std::smatch start, duration;
    if (run.exit_code != 0 ||
        !std::regex_search(run.out, start, std::regex("\"start_ns\":([0-9]+)")) ||
        !std::regex_search(run.out, duration, std::regex("\"duration_s\":([0-9.e+-]+)")))
      return std::make_pair(0.0, 0.0);
    const double from = std::stod(start[1]) * 1e-9;
    return std::make_pair(from, from + std::stod(duration[1]));
  };
  ASSERT_TRUE(wait_until([&] { return span(first).second - span(first).first > 1.0; }, 30s))
      << read_file(log);
  kill(hub.pid, SIGKILL);
  waitpid(hub.pid, nullptr, 0);
  hub.pid = spawn_afhub({"hub"}, "/tmp/afhub-test-hub.log");
  ASSERT_TRUE(wait_until([] { return probe_roudi() == RoudiPresence::kRunning; }, kHubStartWait));
  int status = 0;
  ASSERT_TRUE(
      wait_until([&] { return waitpid(recorder.pid, &status, WNOHANG) == recorder.pid; }, 60s))
      << "the recorder did not end\n"
      << read_file(log);
  recorder.pid = -1;
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << read_file(log);
  const auto [begun, first_end] = span(first);
  const auto [second_start, second_end] = span(second);  // 0s when the hub came back late
  std::printf("--duration 8 across a hub kill: first file %.2f s, second %.2f s, %.2f s in all\n",
              first_end - begun, second_end - second_start,
              std::max(first_end, second_end) - begun);
  EXPECT_LT(std::max(first_end, second_end) - begun, kDurationS + 0.2) << read_file(log);
  EXPECT_EQ(physics.stop(), 0);
}

TEST(HubLoss, TheViewerSaysTheHubIsLostThenServesLiveFramesAgain) {
  const std::string view_log = "/tmp/afhub-fault-view.log",
                    physics_log = "/tmp/afhub-fault-view-physics.log";
  ScopedProcess hub(start_test_hub());
  ASSERT_GT(hub.pid, 0);
  ScopedProcess physics = spawn_afhub(
      {"run", std::string(AFHUB_EXAMPLE_MODELS) + "/arm7.yaml", "--no-autostart"}, physics_log);
  ScopedProcess view = spawn_afhub({"view", "--port", "0"}, view_log);
  int port = 0;
  const std::regex url("http://127\\.0\\.0\\.1:([0-9]+)/");
  ASSERT_TRUE(wait_until(
      [&] {
        std::smatch match;
        const std::string text = read_file(view_log);
        if (!std::regex_search(text, match, url)) return false;
        port = std::stoi(match[1]);
        return true;
      },
      20s))
      << read_file(view_log);
  {
    FrameCounter page(port);
    ASSERT_TRUE(page.connected());
    ASSERT_TRUE(live_frames(page, 20s)) << tail(read_file(view_log));
  }
  int reexecs = 0;
  for (const bool sigkill : {false, true}) {
    const char* loss = sigkill ? "a hub SIGKILL" : "`afhub hub stop --force`";
    if (sigkill) {
      kill(hub.pid, SIGKILL);
    } else {
      ASSERT_EQ(run_afhub({"hub", "stop", "--force"}).exit_code, 0);
    }
    waitpid(hub.pid, nullptr, 0);
    hub.pid = -1;
    // The viewer re-executes to re-attach; its new image says it waits for a hub once it
    // listens again. The page is opened on that image only: the old one, between noticing
    // the loss and its re-exec, sends hub-lost frames too, and the exec then closes a page
    // opened on it (a browser's page reconnects; this one would wait on it for nothing).
    ++reexecs;
    ASSERT_TRUE(wait_until(
        [&] {
          return occurrences(read_file(view_log), "waiting for a hub to re-attach to") >= reexecs;
        },
        20s))
        << "after " << loss << ":\n"
        << tail(read_file(view_log));
    FrameCounter page(port);
    ASSERT_TRUE(page.connected());
    ASSERT_TRUE(wait_until([&] { return says_hub_lost(page.last_frame()); }, 20s))
        << "after " << loss << ":\n"
        << tail(read_file(view_log));
    EXPECT_EQ(exit_code_if_ended(view.pid), -1) << tail(read_file(view_log));

    hub.pid = spawn_afhub({"hub"}, "/tmp/afhub-test-hub.log");
    ASSERT_TRUE(wait_until([] { return probe_roudi() == RoudiPresence::kRunning; }, kHubStartWait));
    // Live again on the connection opened while the hub was lost.
    EXPECT_TRUE(live_frames(page, 30s))
        << "after " << loss << (page.closed() ? " (the viewer closed the page)" : "")
        << ":\nview: " << tail(read_file(view_log))
        << "\nphysics: " << tail(read_file(physics_log));
  }
  EXPECT_EQ(view.stop(), 0) << tail(read_file(view_log));
  EXPECT_EQ(physics.stop(), 0);
}

// Whether `pid` is stopped (SIGSTOP): /proc/PID/stat's state after the command's ")".
bool stopped(pid_t pid) {
  const std::string stat = read_file("/proc/" + std::to_string(pid) + "/stat");
  const std::size_t end = stat.rfind(')');
  return end != std::string::npos && end + 2 < stat.size() && stat[end + 2] == 'T';
}

// The wrapper of a process with a fault hook (tests/faults/*.c) preloaded, its variable
// set. A sanitized afhub wants its runtime first in the preloaded libraries: told not
// to check.
std::vector<std::string> with_hook(const std::string& library, const std::string& variable) {
  const char* asan = std::getenv("ASAN_OPTIONS");
  return {"env", "LD_PRELOAD=" + library, variable,
          "ASAN_OPTIONS=" + std::string(asan && *asan ? asan + std::string(":") : "") +
              "verify_asan_link_order=0"};
}

// ... of a process held once `when` ("BEFORE", "AFTER") it registers
// (tests/faults/stop_around_registration.c).
std::vector<std::string> stopped_around_registration(const std::string& when,
                                                     const std::string& marker) {
  return with_hook(AFHUB_STOP_AROUND_REGISTRATION,
                   "AFHUB_TEST_STOP_" + when + "_REGISTRATION=" + marker);
}

// Ctrl-C just after the hub was lost, while the process re-executes itself to wait for
// the next: the new image had no handlers yet, and the signal ended it with code 130
// (44 of 75 in a fault-injection run, sent 20 to 100 ms after the hub's SIGKILL). The
// stop signals go across the re-exec blocked, and end the wait with code 0 as
// documented. `afhub synth` here, a delay of 0 to 135 ms each round.
TEST(HubLoss, CtrlCJustAfterTheHubIsLostEndsTheProcessWithCodeZero) {
  const std::string log = "/tmp/afhub-fault-ctrl-c.log";
  for (int delay_ms = 0; delay_ms <= 135; delay_ms += 15) {
    SCOPED_TRACE("SIGINT " + std::to_string(delay_ms) + " ms after the hub's SIGKILL");
    ScopedProcess hub(start_test_hub());
    ASSERT_GT(hub.pid, 0);
    ScopedProcess synth = spawn_afhub({"synth", "--bodies", "1", "--no-autostart"}, log);
    ASSERT_TRUE(wait_until([] { return contains(run_afhub({"ls"}, 5s).out, "synth/body0"); }, 20s))
        << read_file(log);
    std::this_thread::sleep_for(300ms);  // past its start: it looks at the catalog every 10 ms
    kill(hub.pid, SIGKILL);
    waitpid(hub.pid, nullptr, 0);
    hub.pid = -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
    kill(synth.pid, SIGINT);
    EXPECT_EQ(wait_for_exit(synth, 20s), 0) << read_file(log);
  }
}

// Ctrl-C in the last moment before the re-exec, taken by another thread than the one
// re-executing (tests/faults/stop_signal_at_exec.c): the flag it set went with the old
// image, and the new one waited for a hub for good. The signal is passed on to the
// re-executing thread, which holds it blocked across the exec.
// Five rounds: half of such rounds ended in the old image without the forwarding.
TEST(HubLoss, CtrlCAsTheProcessReexecutesEndsItWithCodeZero) {
  const std::string marker = "/tmp/afhub-fault-sigint-at-exec";
  const std::string log = "/tmp/afhub-fault-sigint-at-exec.log";
  for (int round = 0; round < 5; ++round) {
    SCOPED_TRACE("round " + std::to_string(round));
    unlink(marker.c_str());
    ScopedProcess hub(start_test_hub());
    ASSERT_GT(hub.pid, 0);
    ScopedProcess synth = spawn_wrapped_afhub(
        with_hook(AFHUB_STOP_SIGNAL_AT_EXEC, "AFHUB_TEST_SIGINT_AT_EXEC=" + marker),
        {"synth", "--bodies", "1", "--no-autostart"}, log);
    ASSERT_TRUE(wait_until([] { return contains(run_afhub({"ls"}, 5s).out, "synth/body0"); }, 20s))
        << read_file(log);
    kill(hub.pid, SIGKILL);
    waitpid(hub.pid, nullptr, 0);
    hub.pid = -1;
    ASSERT_TRUE(wait_until([&] { return access(marker.c_str(), F_OK) == 0; }, 20s))
        << "it did not re-execute\n"
        << read_file(log);
    EXPECT_EQ(wait_for_exit(synth, 10s), 0) << read_file(log);
  }
}

// A hub SIGKILLed while a process registers with it (the process held just before it
// sends its registration: tests/faults/stop_around_registration.c). iceoryx alone waited
// 60 s and aborted, or waited on. A process that outlives its hub (`afhub synth`) waits
// for the next hub and attaches to it; another (`afhub ls`) says so and exits with code 1.
TEST(HubLoss, AHubKilledWhileAProcessRegistersIsSeen) {
  const std::string marker = "/tmp/afhub-fault-registration-stopped";
  for (const bool outlives : {false, true}) {
    SCOPED_TRACE(outlives ? "afhub synth" : "afhub ls");
    const std::string log = "/tmp/afhub-fault-registration.log";
    unlink(marker.c_str());
    ScopedProcess hub(start_test_hub());
    ASSERT_GT(hub.pid, 0);
    const std::vector<std::string> args =
        outlives ? std::vector<std::string>{"synth", "--bodies", "2", "--no-autostart"}
                 : std::vector<std::string>{"ls"};
    ScopedProcess client =
        spawn_wrapped_afhub(stopped_around_registration("BEFORE", marker), args, log);
    ASSERT_TRUE(wait_until([&] { return stopped(client.pid); }, 20s)) << read_file(log);
    ASSERT_TRUE(contains(read_file(log), "stop_around_registration: stopped before"))
        << read_file(log);
    kill(hub.pid, SIGKILL);
    waitpid(hub.pid, nullptr, 0);
    hub.pid = -1;
    kill(client.pid, SIGCONT);
    if (!outlives) {
      EXPECT_EQ(wait_for_exit(client, 20s), 1) << read_file(log);
      EXPECT_TRUE(contains(read_file(log), "went away while registering this process"))
          << read_file(log);
      continue;
    }
    ASSERT_TRUE(wait_until(
        [&] { return contains(read_file(log), "waiting for a hub to re-attach to"); }, 20s))
        << read_file(log);
    EXPECT_TRUE(contains(read_file(log), "went away (while registering this process)"))
        << read_file(log);
    hub.pid = start_test_hub();
    ASSERT_GT(hub.pid, 0);
    EXPECT_TRUE(wait_until([&] { return contains(read_file(log), "re-attached to the hub"); }, 20s))
        << read_file(log);
    EXPECT_TRUE(wait_until([] { return contains(run_afhub({"ls"}, 5s).out, "synth/body0"); }, 20s))
        << run_afhub({"ls"}, 5s).out << read_file(log);
    EXPECT_EQ(client.stop(SIGINT), 0) << read_file(log);
  }
}

// A hub replaced (SIGKILLed, a new one started) just after a process registered with it,
// before the process read which hub it is attached to (the process held at that read:
// tests/faults/stop_around_registration.c). It took the new hub for its own and stayed on
// the dead one's memory: not in the new hub's `afhub ls`, or, at its next iceoryx error,
// re-executed to wait for a hub other than the live one, for good (a fault-injection run:
// hubs killed and restarted 20 to 110 ms apart, 2 rounds in 14). The hub it registered
// with is the one it saw before registering: the watcher sees it replaced, and the
// process re-attaches to the new one.
TEST(HubLoss, AHubReplacedJustAfterAProcessRegisteredIsSeen) {
  const std::string marker = "/tmp/afhub-fault-registration-stopped-after";
  const std::string log = "/tmp/afhub-fault-registration-after.log";
  ScopedProcess hub(start_test_hub());
  ASSERT_GT(hub.pid, 0);
  ScopedProcess client = spawn_wrapped_afhub(stopped_around_registration("AFTER", marker),
                                             {"synth", "--bodies", "2", "--no-autostart"}, log);
  ASSERT_TRUE(wait_until([&] { return stopped(client.pid); }, 20s)) << read_file(log);
  ASSERT_TRUE(contains(read_file(log), "stop_around_registration: stopped after"))
      << read_file(log);
  kill(hub.pid, SIGKILL);
  waitpid(hub.pid, nullptr, 0);
  hub.pid = start_test_hub();
  ASSERT_GT(hub.pid, 0);
  kill(client.pid, SIGCONT);
  const std::string reattached = "re-attached to the hub (pid " + std::to_string(hub.pid) + ")";
  EXPECT_TRUE(wait_until([&] { return contains(read_file(log), reattached); }, 20s))
      << read_file(log);
  EXPECT_TRUE(wait_until([] { return contains(run_afhub({"ls"}, 5s).out, "synth/body0"); }, 20s))
      << run_afhub({"ls"}, 5s).out << read_file(log);
  EXPECT_EQ(client.stop(SIGINT), 0) << read_file(log);
}

INSTANTIATE_TEST_SUITE_P(Faults, HubRestart, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& param) {
                           return param.param ? std::string("HubSigkill") : std::string("HubStop");
                         });

}  // namespace
}  // namespace afhub::test
