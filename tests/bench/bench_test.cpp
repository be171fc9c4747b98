// `afhub bench` end to end, briefly: every transport with real peer processes, the
// 1 kHz loop against the real physics beside cyclictest, the JSON and the plot;
// `afhub bench wake`, the loop's wake-up latency by real-time setting.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <filesystem>

#include "afhub/hub/hub_presence.hpp"
#include "afhub/rt/cpu_wake_latency.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/slot_block.hpp"
#include "afhub_process.hpp"
#include "model_files.hpp"
#include "real_time.hpp"
#include "strict_json.hpp"

namespace afhub::test {
namespace {

using namespace std::chrono_literals;

// No hub runs: the bench starts one with the pools it needs (a production hub has none),
// and stops it; stopped here too should the bench fail.
class BenchOwnHub : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(probe_roudi(), RoudiPresence::kAbsent) << "stop the running hub first";
  }
  void TearDown() override { run_afhub({"hub", "stop"}); }
};

TEST_F(BenchOwnHub, ShortRunMeasuresEveryTransportAndTheLoop) {
  afhub::testing::ModelFolder folder;
  const std::string json_path = (folder.dir() / "bench.json").string();
  const std::string plot_path = (folder.dir() / "bench.png").string();
  const RunResult run = run_afhub({"bench", "--rounds", "2", "--pings", "25", "--loop-seconds", "3",
                                   "--json", json_path, "--plot", plot_path},
                                  180s);
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  // The hub it started is gone with it: the next program must not land on its pools.
  EXPECT_EQ(probe_roudi(), RoudiPresence::kAbsent) << "the bench left its hub running";
  EXPECT_FALSE(contains(run.err, "FAILED")) << run.err;
  EXPECT_TRUE(contains(run.out, "One-way latency, median")) << run.out;
  EXPECT_TRUE(contains(run.out, "Goals")) << run.out;
  EXPECT_TRUE(contains(run.err, "latency round 2 of 2")) << run.err;  // progress
  // Nothing of it left in /tmp (the test binary's own): rosmaster's home, the physics'
  // step log and the peers' logs, kept only when a run fails, go with it.
  for (const auto& entry : std::filesystem::directory_iterator("/tmp")) {
    const std::string name = entry.path().filename().string();
    EXPECT_FALSE(name.starts_with("afhub-bench-ros-") ||
                 (name.starts_with("afhub-bench-") &&
                  (name.ends_with(".log") || name.ends_with("-steps.txt"))))
        << entry.path();
  }

  const nlohmann::json json = parse_json(read_file(json_path));
  const nlohmann::json& transports = json.at("transports");
  for (const char* name : {"afhub", "afhub-slot", "shm-floor", "dds", "dds-shm", "uds", "ros1"}) {
    ASSERT_TRUE(transports.contains(name)) << name << " missing: " << read_file(json_path);
    for (const char* bytes : {"64", "1024", "16384", "262144", "1048576"}) {
      const nlohmann::json& one_way = transports.at(name).at(bytes);
      const nlohmann::json& round_trip = json.at("round_trip").at(name).at(bytes);
      // 2 rounds x 25 pings, each giving two one-way samples and one round trip.
      EXPECT_EQ(one_way.at("samples"), 100) << name << " " << bytes;
      EXPECT_EQ(round_trip.at("samples"), 50) << name << " " << bytes;
      const double p50 = one_way.at("p50_us").get<double>();
      EXPECT_GT(p50, 0.0) << name << " " << bytes;
      EXPECT_LE(p50, one_way.at("p99_us").get<double>());
      EXPECT_LE(one_way.at("p99_us").get<double>(), one_way.at("max_us").get<double>());
      // Each way is part of the round trip.
      EXPECT_LT(p50, round_trip.at("p50_us").get<double>()) << name << " " << bytes;
    }
  }
  // The loop ran 3 s at 1 kHz, and so did cyclictest.
  const nlohmann::json& jitter = json.at("loop_jitter");
  EXPECT_EQ(jitter.at("afhub_us").at("samples"), 3000);
  EXPECT_EQ(jitter.at("cyclictest_us").at("samples"), 3000);
  EXPECT_GT(jitter.at("afhub_us").at("p50").get<double>(), 0.0);
  EXPECT_GT(jitter.at("cyclictest_us").at("p50").get<double>(), 0.0);
  const double ratio = json.at("loop_deadline_hit_ratio").get<double>();
  EXPECT_GE(ratio, 0.0);
  EXPECT_LE(ratio, 1.0);
  EXPECT_GT(json.at("loop_steps").get<double>(), 2000.0);

  // A PNG came out.
  ASSERT_TRUE(std::filesystem::exists(plot_path));
  EXPECT_EQ(read_file(plot_path).substr(1, 3), "PNG");
  EXPECT_GT(std::filesystem::file_size(plot_path), 20'000u);

  // The controller answering steps in time needs real time: in a sanitized build beside
  // the two-machine teleop test's SCHED_FIFO loops it once answered none of 2000.
  std::printf("loop deadline hit ratio: %.3f\n", ratio);
  SKIP_REAL_TIME_BOUNDS_IN_SANITIZED_BUILD();
  EXPECT_GT(ratio, 0.9);  // below it, the bench exits 1 (above)
}

// --touch: every sender writes every byte of its messages and every receiver reads and
// checks them, each round a new pattern: a transport whose sender left the bytes as
// they were, or whose receiver saw other bytes, would fail the run.
TEST_F(BenchOwnHub, TouchWritesAndReadsEveryByte) {
  afhub::testing::ModelFolder folder;
  const std::string json_path = (folder.dir() / "bench.json").string();
  const RunResult run =
      run_afhub({"bench", "--touch", "--transports", "afhub,afhub-slot,shm-floor,dds,dds-shm,uds",
                 "--rounds", "2", "--pings", "10", "--loop-seconds", "0", "--json", json_path},
                180s);
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_TRUE(contains(run.out, "Messages: every byte written by the sender and read")) << run.out;
  // The slot is set against the machine's floor measured in the same run.
  EXPECT_TRUE(contains(run.out, "afhub-slot against shm-floor (bare shared memory")) << run.out;
  const nlohmann::json json = parse_json(read_file(json_path));
  EXPECT_EQ(json.at("settings").at("touch"), true) << read_file(json_path);
  for (const char* name : {"afhub", "afhub-slot", "shm-floor", "dds", "dds-shm", "uds"})
    EXPECT_EQ(json.at("transports").at(name).at("1048576").at("samples"), 40) << name;
}

// A peer killed in the middle of the run: the bench ends at its next ping, naming the
// transport whose peer is gone and keeping its log, instead of a bare "did not answer".
TEST_F(BenchOwnHub, AKilledPeerIsSaid) {
  afhub::testing::ModelFolder folder;
  const std::string log = (folder.dir() / "bench.log").string();
  ScopedProcess bench(spawn_afhub(
      {"bench", "--transports", "uds,shm-floor", "--rounds", "1000", "--loop-seconds", "0"}, log));
  ASSERT_TRUE(wait_until([&] { return contains(read_file(log), "latency round 1 of"); }, 60s))
      << read_file(log);
  // This bench's own peer: a developer's bench elsewhere on the machine is left alone.
  ASSERT_EQ(run_command(
                {"pkill", "-KILL", "-P", std::to_string(bench.pid), "-f", "bench --peer shm-floor"})
                .exit_code,
            0);
  EXPECT_EQ(wait_for_exit(bench, 30s), 1) << read_file(log);
  const std::string said = read_file(log);
  EXPECT_TRUE(contains(said, "shm-floor: the peer did not answer a ")) << said;
  const std::string kept = "; it exited (see /tmp/afhub-bench-";
  ASSERT_TRUE(contains(said, kept)) << said;
  // The log it kept, gone with the test: another test looks for leftovers.
  const std::size_t from = said.find(kept) + kept.size() - std::string("/tmp/afhub-bench-").size();
  std::filesystem::remove(said.substr(from, said.find(')', from) - from));
}

// A hub whose pools starve the body states (`--pool` of 6 chunks just large enough for
// the example arm's state slots, below the body tiers: they all come from it, one per
// body of the 8): the bench fails loudly, naming the pool, instead of reporting "met"
// (it said 1.7 % in time, exit 0). Either the physics starts, drops states and says so
// once, or it is refused at start for the lack of spare chunks.
TEST(Bench, StarvedBodyStatesFailTheBench) {
  // The block of arm/base's state slot, the arm's largest (7 joints below it).
  const std::string bytes = std::to_string(
      afhub::slot_block_pool_bytes(afhub::first_slot_block_bytes(afhub::body_state_bytes(7))));
  ScopedProcess hub(spawn_afhub({"hub", "--bench-pools", "--pool", bytes + ":6"}));
  ASSERT_TRUE(wait_until(
      [] { return probe_roudi() == RoudiPresence::kRunning && running_hub_pid(); }, 10s));
  const RunResult run = run_afhub(
      {"bench", "--transports", "afhub", "--rounds", "1", "--pings", "5", "--loop-seconds", "2"},
      120s);
  EXPECT_EQ(run.exit_code, 1) << run.out << run.err;
  const std::string pool = "chunks of " + bytes + " bytes";
  const bool dropped = contains(run.err,
                                "afhub bench: FAILED: the physics did not publish every step's "
                                "states: it said \"afhub physics: shared memory exhausted: the "
                                "hub's pool of ") &&
                       contains(run.err, pool + " has none free");
  const bool refused =
      contains(run.err, "The physics ended (exit code 1)") && contains(run.err, pool);
  EXPECT_TRUE(dropped || refused) << run.err;
  if (dropped) {
    EXPECT_TRUE(contains(run.out, "(goal >= 99 %): NOT met")) << run.out;
  }
  std::printf("the physics %s\n", dropped ? "dropped states" : "was refused at start");
  EXPECT_EQ(probe_roudi(), RoudiPresence::kRunning) << "the bench stopped a hub it did not start";
}

TEST(Bench, RunningHubWithoutBenchPoolsIsRefusedSayingWhatToDo) {
  ScopedProcess hub(spawn_afhub({"hub"}));
  ASSERT_TRUE(wait_until(
      [] { return probe_roudi() == RoudiPresence::kRunning && running_hub_pid(); }, 10s));
  const RunResult run = run_afhub({"bench", "--transports", "afhub", "--loop-seconds", "0"}, 60s);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_TRUE(contains(run.err, "free chunks for 1048576 byte samples; the bench needs 16"))
      << run.err;
  EXPECT_TRUE(contains(run.err, "afhub hub --bench-pools")) << run.err;
}

// Each setting's loop ran its 1000 cycles in a process of its own, and its figures
// are a distribution (their size is this machine's: no bound is asserted). The settings
// that need privileges may be refused, saying why; the normal scheduler's never are.
TEST(Bench, WakeMeasuresEveryRealTimeSetting) {
  const RunResult run = run_afhub({"bench", "wake", "--rounds", "2", "--seconds", "0.5"}, 120s);
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_TRUE(contains(run.err, "round 2 of 2")) << run.err;
  EXPECT_TRUE(contains(run.out, "2 round(s) of 0.5 s per setting")) << run.out;
  const bool root = geteuid() == 0 && access(kCpuWakeLatencyDevice, W_OK) == 0;
  for (const char* setting :
       {"normal scheduler, the default timer slack", "normal scheduler (afhub: 1 ns timer slack)",
        "normal scheduler, --cpu-wake-latency 0", "--fifo 80", "--fifo 80 --cpu-wake-latency 0"}) {
    const std::size_t at = run.out.find(std::string(setting) + "  ");
    ASSERT_NE(at, std::string::npos) << setting << " missing:\n" << run.out;
    const std::size_t from = at + std::strlen(setting);
    const std::string line = run.out.substr(from, run.out.find('\n', from) - from);
    const bool privileged = contains(setting, "fifo") || contains(setting, "wake-latency");
    if (contains(line, "refused: ")) {
      EXPECT_TRUE(privileged && !root) << setting << ": " << line;
      continue;
    }
    double p50 = 0, p99 = 0, p999 = 0, max = 0, cycles = 0;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf %lf %lf %lf %lf", &p50, &p99, &p999, &max, &cycles), 5)
        << setting << ": " << line;
    EXPECT_EQ(cycles, 1000.0) << setting;  // 2 rounds of 500 cycles at 1 kHz
    EXPECT_GT(p50, 0.0) << setting;
    EXPECT_LE(p50, p99) << setting;
    EXPECT_LE(p99, p999) << setting;
    EXPECT_LE(p999, max) << setting;
  }
  RunResult bad = run_afhub({"bench", "wake", "--seconds", "0"});
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_TRUE(contains(bad.err, "--seconds takes 0.1 to 3600 seconds")) << bad.err;
}

// The many-body world across processes, small: each step's phases come from the
// physics' own step log, the commands counted from its world state. No bound on a
// time is asserted (they are this machine's), only what holds on any machine.
TEST_F(BenchOwnHub, BodiesTimesEachStepsPhasesAcrossProcesses) {
  const RunResult run =
      run_afhub({"bench", "bodies", "--arms", "4", "--links", "3", "--seconds", "2"}, 120s);
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_EQ(probe_roudi(), RoudiPresence::kAbsent) << "the bench left its hub running";
  EXPECT_FALSE(contains(run.err, "FAILED")) << run.err;
  double steps = 0;
  ASSERT_EQ(
      std::sscanf(run.out.c_str(), "4 arms of 3 links, 12 bodies at 1 kHz, %lf steps", &steps), 1)
      << run.out;
  // 2 s measured at 1 kHz: a physics cannot take many more steps than milliseconds
  // pass (a catch-up after a stall makes up at most 100), and some were measured.
  EXPECT_GT(steps, 100.0) << run.out;
  EXPECT_LE(steps, 2200.0) << "steps from outside the measured window:\n" << run.out;
  const auto row = [&](const char* name, double& p50, double& p99) {
    const std::size_t at = run.out.find(name);
    ASSERT_NE(at, std::string::npos) << name << " missing:\n" << run.out;
    ASSERT_EQ(std::sscanf(run.out.c_str() + at + std::strlen(name), "%lf %lf", &p50, &p99), 2)
        << name << ":\n"
        << run.out;
    EXPECT_LE(p50, p99) << name;
  };
  double whole50 = 0, whole99 = 0, commands50 = 0, commands99 = 0, physics50 = 0, physics99 = 0,
         publish50 = 0, publish99 = 0, controller50 = 0, controller99 = 0;
  row("the whole step", whole50, whole99);
  row("commands read and applied", commands50, commands99);
  row("physics (Bullet's step, joint records)", physics50, physics99);
  row("states published", publish50, publish99);
  row("The controller writing every command, us", controller50, controller99);
  // Each phase took time in most steps: commands were read, the world stepped, states
  // published (a phase left unmeasured reads 0).
  EXPECT_GT(commands50, 0.0) << run.out;
  EXPECT_GT(physics50, 0.0) << run.out;
  EXPECT_GT(publish50, 0.0) << run.out;
  EXPECT_GT(controller50, 0.0) << run.out;
  double in_time = 0, body_steps = 0;
  const std::size_t at = run.out.find("Commands in time for the next step: ");
  ASSERT_NE(at, std::string::npos) << run.out;
  ASSERT_EQ(std::sscanf(run.out.c_str() + at, "Commands in time for the next step: %lf %% of %lf",
                        &in_time, &body_steps),
            2)
      << run.out;
  EXPECT_GE(body_steps, 12.0 * 100) << "the physics counted few commanded steps:\n" << run.out;
  EXPECT_TRUE(contains(run.out, "Goals: set for 1000 bodies or more")) << run.out;
  // Its scene, step log and the physics' log are gone with it (this /tmp is the test
  // binary's).
  for (const auto& entry : std::filesystem::directory_iterator("/tmp")) {
    const std::string name = entry.path().filename().string();
    EXPECT_FALSE(name.starts_with("afhub-bench-") &&
                 (name.ends_with("-arms.yaml") || name.ends_with("-steps.txt") ||
                  name.ends_with("-physics.log")))
        << entry.path();
  }

  const RunResult bad = run_afhub({"bench", "bodies", "--arms", "0"});
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_TRUE(contains(bad.err, "--arms takes 1 to 500 and --links 2 to 16")) << bad.err;
  const RunResult both = run_afhub({"bench", "bodies", "--quick", "--seconds", "3"});
  EXPECT_NE(both.exit_code, 0);
  EXPECT_TRUE(contains(both.err, "excludes")) << both.err;
}

TEST(Bench, BadArgumentsAreRefusedClearly) {
  RunResult run = run_afhub({"bench", "--transports", "afhub,zeromq", "--loop-seconds", "0"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_TRUE(contains(
      run.err,
      "unknown transport 'zeromq': choose from afhub, afhub-slot, shm-floor, dds, dds-shm, uds, "
      "ros1"))
      << run.err;
  run = run_afhub({"bench", "--loop-seconds", "1"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_TRUE(contains(run.err, "--loop-seconds must be 0 (skip the loop) or at least 2"))
      << run.err;
}

}  // namespace
}  // namespace afhub::test
