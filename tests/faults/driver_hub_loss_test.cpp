// A device driver whose hub goes away while it applies force: the force goes to zero and
// the device is made safe (by the driver's own loop) before the driver re-executes to
// re-attach; once a new hub is up, the driver publishes again and applies force again.
// The virtual device's force log (--force-log) shows what a real device would be
// given. The commanding client keeps writing into the dead hub's memory, and the
// driver's watchdog is 1 s: only the hub-loss handling can zero the force in time.
//
// The test process never joins the first hub; it looks through `afhub` commands.
#include <gtest/gtest.h>
#include <signal.h>

#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "afhub/shm_layout/header.hpp"
#include "afhub_process.hpp"
#include "hub_environment.hpp"

namespace afhub::test {
namespace {

using namespace std::chrono_literals;

const std::string kForceLog = "/tmp/afhub-safe-hand.force";
const std::string kDriverLog = "/tmp/afhub-safe-hand.log";

struct LogLine {
  std::int64_t ns = 0;
  std::string what;  // "force", "zero", "made safe", "open"
};

std::vector<LogLine> force_log() {
  std::vector<LogLine> lines;
  std::istringstream text(read_file(kForceLog));
  for (std::string line; std::getline(text, line);) {
    std::istringstream fields(line);
    LogLine entry;
    std::string word;
    fields >> entry.ns >> word;
    entry.what = word == "made" ? "made safe" : word;
    lines.push_back(entry);
  }
  return lines;
}

// The index of the first line at or after `from` saying `what`, or -1.
int find(const std::vector<LogLine>& lines, const std::string& what, std::size_t from = 0) {
  for (std::size_t i = from; i < lines.size(); ++i)
    if (lines[i].what == what) return static_cast<int>(i);
  return -1;
}

std::string log_text() {
  return "force log:\n" + read_file(kForceLog) + "driver:\n" + read_file(kDriverLog);
}

TEST(DriverHubLoss, ForceGoesToZeroBeforeTheDriverReattachesAndPublishesAgain) {
  // Whatever happens below, the hub of the moment is stopped at the end.
  ScopedProcess hub(start_test_hub());
  ASSERT_GT(hub.pid, 0);
  std::remove(kForceLog.c_str());

  ScopedProcess driver =
      spawn_afhub({"device", "run", "virtual", "--name", "safe_hand", "--force-log", kForceLog,
                   "--ramp", "0", "--watchdog", "1000"},
                  kDriverLog);
  ScopedProcess force =
      spawn_afhub({"device", "force", "safe_hand", "--force", "0,0,2", "--wait", "10"},
                  "/tmp/afhub-safe-hand-force.log");
  ASSERT_TRUE(wait_until([] { return find(force_log(), "force") >= 0; }, 20s)) << log_text();

  const std::int64_t killed_ns = monotonic_ns();
  hub.stop(SIGKILL);
  // The driver re-executes: its new image opens the device again.
  ASSERT_TRUE(wait_until([] { return find(force_log(), "open", 1) >= 0; }, 10s)) << log_text();
  const std::vector<LogLine> lines = force_log();
  const int reopened = find(lines, "open", 1);
  const int applying = find(lines, "force");
  ASSERT_LT(applying, reopened);
  // The last state of the old image: zero force, made safe, both after the force and
  // before the re-exec; nothing applied in between.
  int zero = -1, made_safe = -1;
  for (int i = applying + 1; i < reopened; ++i) {
    if (lines[i].what == "force") zero = made_safe = -1;
    if (lines[i].what == "zero" && zero < 0) zero = i;
    if (lines[i].what == "made safe" && made_safe < 0) made_safe = i;
  }
  ASSERT_GE(made_safe, 0) << "the device was not made safe before the re-exec\n" << log_text();
  const int first_safe = zero >= 0 && zero < made_safe ? zero : made_safe;
  const std::int64_t to_zero_ns = lines[first_safe].ns - killed_ns;
  const std::int64_t to_made_safe_ns = lines[made_safe].ns - killed_ns;
  std::printf("hub SIGKILLed -> force zero %.1f ms, -> made safe %.1f ms, -> re-exec %.1f ms\n",
              to_zero_ns * 1e-6, to_made_safe_ns * 1e-6, (lines[reopened].ns - killed_ns) * 1e-6);
  // How soon is reported, not asserted (the loss is seen within about 40 ms, two looks
  // at the hub 20 ms apart, on a quiet machine; a loaded one stretches it). What is
  // asserted is the order: force, the hub's death, zero and made safe, the re-exec.
  RecordProperty("to_zero_us", static_cast<int>(to_zero_ns / 1000));
  RecordProperty("to_made_safe_us", static_cast<int>(to_made_safe_ns / 1000));
  EXPECT_GE(to_zero_ns, 0) << "the force went to zero before the hub was killed\n" << log_text();
  // Made safe by the device's loop: asked by the thread that saw the loss, or itself, when
  // its own iceoryx call saw it first (a loaded machine, twice in about 40 runs); never
  // from another thread after the loop failed to answer.
  EXPECT_FALSE(contains(read_file(kDriverLog), "the device's loop did not answer")) << log_text();

  // A new hub: the driver re-attaches, publishes its state, and applies a new client's force.
  hub.pid = start_test_hub();
  ASSERT_GT(hub.pid, 0);
  force.stop();
  ScopedProcess new_force =
      spawn_afhub({"device", "force", "safe_hand", "--force", "0,0,2", "--wait", "10"},
                  "/tmp/afhub-safe-hand-force.log");
  EXPECT_TRUE(wait_until([&] { return find(force_log(), "force", reopened) >= 0; }, 20s))
      << "the driver applies no force after the new hub came\n"
      << log_text();
  const RunResult echo = run_afhub({"echo", "safe_hand", "-n", "1", "--json"}, 10s);
  EXPECT_EQ(echo.exit_code, 0) << echo.err;
  EXPECT_TRUE(contains(echo.out, "applied")) << echo.out;
  EXPECT_TRUE(contains(read_file(kDriverLog), "re-attached to the hub")) << log_text();
}

}  // namespace
}  // namespace afhub::test
