// The afhub command line end to end: hub lifecycle, autostart, tools without a
// hub, and ls / echo / cmd / status against synthetic bodies.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>

#include "afhub/hub/hub_files.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/slot_block.hpp"
#include "afhub_process.hpp"
#include "hub_environment.hpp"
#include "model_files.hpp"
#include "shared_models.hpp"
#include "strict_json.hpp"
#include "web_client.hpp"

namespace afhub::test {
namespace {

using namespace std::chrono_literals;

void expect_no_hub() {
  ASSERT_NE(probe_roudi(), RoudiPresence::kRunning) << "a hub is running before the test";
}

TEST(Cli, EveryCommandHasHelp) {
  for (const char* command :
       {"hub", "ls", "echo", "cmd", "status", "synth", "demo", "check", "run", "world", "ctl"}) {
    RunResult help = run_afhub({command, "--help"});
    EXPECT_EQ(help.exit_code, 0) << command;
    EXPECT_TRUE(contains(help.out, "Usage")) << command << ": " << help.out;
  }
  RunResult bad = run_afhub({"frobnicate"});
  EXPECT_NE(bad.exit_code, 0);
}

// Any exception, not only afhub's own, ends a command with its message and exit 1,
// never std::terminate: a path longer than the system allows makes
// std::filesystem throw from the demo's model check.
TEST(Cli, AnUnexpectedExceptionIsAnErrorNotACrash) {
  expect_no_hub();
  RunResult demo = run_afhub({"demo", "--model", std::string(5000, 'a')});
  EXPECT_EQ(demo.exit_code, 1) << demo.err.substr(0, 300);
  EXPECT_TRUE(contains(demo.err, "afhub demo: error: ")) << demo.err.substr(0, 300);
  EXPECT_TRUE(contains(demo.err, "File name too long")) << demo.err.substr(0, 300);
  EXPECT_FALSE(contains(demo.err, "terminate")) << demo.err.substr(0, 300);
}

TEST(Cli, DemoSimulatesTheExampleSceneLive) {
  expect_no_hub();
  RunResult demo = run_afhub({"demo", "--seconds", "3", "--no-view"}, 30s);
  EXPECT_EQ(demo.exit_code, 0) << demo.err;
  EXPECT_TRUE(contains(demo.err, "no hub was running; started one")) << demo.err;
  // The example scene: the arm, the remote-centre-of-motion arm and the gripper.
  EXPECT_TRUE(contains(demo.err, "afhub run: 19 bodies, 19 joints on channels")) << demo.err;
  for (const char* body : {"afhub/arm/link7", "afhub/rcm/insertion_link", "afhub/gripper/palm"})
    EXPECT_TRUE(contains(demo.out, body)) << body << " missing:\n" << demo.out;
  EXPECT_FALSE(contains(demo.out, "http://")) << "--no-view starts no viewer";
  // A rate not measured yet (the first seconds) is "-", as in `afhub ls`: it said 0.0.
  std::istringstream lines(demo.out);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream fields(line);
    std::string body, rate;
    if (fields >> body >> rate && body == "afhub/arm/link7") {
      EXPECT_NE(rate, "0.0") << line;
    }
  }
  EXPECT_EQ(run_afhub({"hub", "stop"}).exit_code, 0);
}

// The body the demo's first line suggests echoing is one of the model shown (with
// --model it named the example arm's link7, which another model has not).
TEST(Cli, TheDemosHintNamesABodyOfItsModel) {
  expect_no_hub();
  RunResult demo = run_afhub(
      {"demo", "--model", AFHUB_EXAMPLE_MODELS "/gripper.yaml", "--seconds", "2", "--no-view"},
      30s);
  EXPECT_EQ(demo.exit_code, 0) << demo.err;
  const std::regex hint("`afhub echo ([^`]+)`");
  int hints = 0;
  for (auto it = std::sregex_iterator(demo.out.begin(), demo.out.end(), hint);
       it != std::sregex_iterator(); ++it, ++hints)
    EXPECT_TRUE(contains(demo.out, "\n" + (*it)[1].str() + " "))
        << (*it)[1] << " is not in the table:\n"
        << demo.out;
  EXPECT_GT(hints, 0) << demo.out;
  EXPECT_EQ(run_afhub({"hub", "stop"}).exit_code, 0);
}

// The demo starts `afhub view` beside it and prints its URL, which serves the page
// and the example scene; the viewer stops with the demo.
TEST(Cli, DemoPrintsTheViewersUrlWhichServesTheScene) {
  expect_no_hub();
  char pattern[] = "/tmp/afhub_demo_view_XXXXXX";
  ASSERT_NE(mkdtemp(pattern), nullptr);
  const std::string dir = pattern, log = dir + "/demo.log", opened = dir + "/opened";
  // At a desktop the demo opens the URL with xdg-open: a stand-in records what it got.
  std::ofstream(dir + "/xdg-open") << "#!/bin/sh\necho \"$1\" > " << opened << "\n";
  chmod((dir + "/xdg-open").c_str(), 0755);
  const std::string path = std::getenv("PATH");
  setenv("PATH", (dir + ":" + path).c_str(), 1);
  setenv("DISPLAY", ":99", 1);
  ScopedProcess demo(spawn_afhub({"demo", "--seconds", "60", "--view-port", "0"}, log));
  setenv("PATH", path.c_str(), 1);
  unsetenv("DISPLAY");
  const std::regex said("the viewer: http://127\\.0\\.0\\.1:([0-9]+)/");
  int port = 0;
  ASSERT_TRUE(wait_until(
      [&] {
        std::smatch match;
        const std::string text = read_file(log);
        if (!std::regex_search(text, match, said)) return false;
        port = std::stoi(match[1]);
        return true;
      },
      20s))
      << read_file(log);
  const HttpReply page = http_request(port, "GET", "/");
  EXPECT_EQ(page.status, 200);
  EXPECT_TRUE(contains(page.body, "/viewer.js")) << page.body;
  HttpReply scene;
  EXPECT_TRUE(wait_until(
      [&] {
        scene = http_request(port, "GET", "/scene.json");
        return contains(scene.body, "afhub/arm/link7") && contains(scene.body, "afhub/rcm/");
      },
      10s))
      << scene.body;
  EXPECT_TRUE(wait_until(
      [&] { return contains(read_file(opened), ":" + std::to_string(port) + "/"); }, 10s))
      << "the browser was not opened on the viewer's URL: '" << read_file(opened) << "'";
  // It stops its viewer and physics first: under load that took over 5 s once.
  EXPECT_EQ(demo.stop(SIGTERM, 30s), 0) << read_file(log);
  EXPECT_EQ(http_request(port, "GET", "/").status, 0) << "the viewer outlived the demo";
  EXPECT_EQ(run_afhub({"hub", "stop"}).exit_code, 0);
}

// --step-log: one line per step, its start and duration, its point on the grid and the
// commands late for it, for measurements in windows of one run (bench/viewer_cost.sh,
// `afhub bench bodies`); it needs --steps, which sizes it.
TEST(Cli, RunWritesAStepLog) {
  char pattern[] = "/tmp/afhub_step_log_XXXXXX";
  ASSERT_NE(mkdtemp(pattern), nullptr);
  const std::string log = std::string(pattern) + "/steps.txt";
  const std::string arm = AFHUB_EXAMPLE_MODELS "/arm7.yaml";
  RunResult run = run_afhub({"run", arm, "--offline", "--steps", "300", "--step-log", log}, 30s);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  std::istringstream lines(read_file(log));
  std::string header;
  std::getline(lines, header);
  EXPECT_EQ(header, "begin_ns step_us commands_us publish_us due_ns late");
  long long begin = 0, previous = 0, due = 0, previous_due = 0;
  double duration = 0.0, commands = 0.0, publish = 0.0;
  unsigned late = 0;
  int steps = 0;
  while (lines >> begin >> duration >> commands >> publish >> due >> late) {
    EXPECT_GT(begin, previous) << "line " << steps + 2;
    EXPECT_GT(duration, 0.0) << "line " << steps + 2;
    EXPECT_EQ(commands, 0.0) << "line " << steps + 2;  // offline: no channels, no commands
    EXPECT_LT(publish, duration) << "line " << steps + 2;
    EXPECT_GE(begin, due) << "line " << steps + 2;  // a step starts once it is due
    if (steps > 0) {  // on the 1 ms grid: the next point, or one past the periods skipped
      EXPECT_GT(due, previous_due) << "line " << steps + 2;
      EXPECT_EQ((due - previous_due) % 1'000'000, 0) << "line " << steps + 2;
    }
    EXPECT_EQ(late, 0U) << "line " << steps + 2;  // nothing under command
    previous = begin;
    previous_due = due;
    ++steps;
  }
  EXPECT_EQ(steps, 300);
  RunResult unbounded = run_afhub({"run", arm, "--offline", "--step-log", log});
  EXPECT_EQ(unbounded.exit_code, 1);
  EXPECT_TRUE(contains(unbounded.err, "--step-log needs --steps N")) << unbounded.err;
}

TEST(Cli, CheckReportsAModelOrWhereItIsWrong) {
  RunResult rcm = run_afhub({"check", AFHUB_EXAMPLE_MODELS "/rcm.yaml"});
  EXPECT_EQ(rcm.exit_code, 0) << rcm.err;
  EXPECT_TRUE(contains(rcm.out, "closed loops: 2")) << rcm.out;
  RunResult missing = run_afhub({"check", "/nonexistent/model.yaml"});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_TRUE(contains(missing.err, "/nonexistent/model.yaml: error: no such file")) << missing.err;
}

TEST(Cli, CheckReportsTheAmbfFourBar) {
  SKIP_WITHOUT_SHARED_MODELS();
  const std::string models = AFHUB_SHARED_MODELS "/descriptions/multi-bodies/";
  RunResult four_bar = run_afhub({"check", models + "puzzles/parallel_structure.yaml"});
  EXPECT_EQ(four_bar.exit_code, 0) << four_bar.err;
  EXPECT_TRUE(contains(four_bar.out, "bodies: 5 (total mass 4.000 kg)")) << four_bar.out;
  EXPECT_TRUE(contains(four_bar.out, "closed loops: 1")) << four_bar.out;
  EXPECT_TRUE(contains(four_bar.err, "parallel_structure.yaml:131:3: warning:")) << four_bar.err;
}

// The KUKA's file sets gravity 0, which by AMBF's rule wins over the world's:
// `check` says so, and --gravity overrides both, in `check` and in `run`. Both say
// which joint gains the stability cap lowered, with the values used.
TEST(Cli, CheckAndRunSayTheGravityAndTheLoweredGains) {
  SKIP_WITHOUT_SHARED_MODELS();
  const std::string kuka =
      AFHUB_SHARED_MODELS "/descriptions/multi-bodies/robots/blender-kuka.yaml";
  RunResult check = run_afhub({"check", kuka});
  EXPECT_EQ(check.exit_code, 0) << check.err;
  EXPECT_TRUE(contains(check.out, "gravity: world (0, 0, -9.81) m/s^2 (default)")) << check.out;
  EXPECT_TRUE(contains(check.out, "8 bodies fall under (0, 0, 0) m/s^2")) << check.out;
  EXPECT_TRUE(contains(check.out, "lowered to")) << check.out;
  EXPECT_TRUE(contains(check.out, "blender-kuka.yaml:")) << check.out;
  RunResult overridden = run_afhub({"check", kuka, "--gravity", "0,0,-9.81"});
  EXPECT_TRUE(contains(overridden.out, "gravity: world (0, 0, -9.81) m/s^2 (--gravity)"))
      << overridden.out;
  EXPECT_FALSE(contains(overridden.out, "bodies fall under")) << overridden.out;
  RunResult bad = run_afhub({"check", kuka, "--gravity", "0,-9.81"});
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_TRUE(contains(bad.err, "--gravity")) << bad.err;
  // Gravity in mm/s^2 is warned of, and counted in the report's total.
  RunResult wrong_unit = run_afhub({"check", kuka, "--gravity", "0,0,-9810"});
  EXPECT_EQ(wrong_unit.exit_code, 0) << wrong_unit.err;
  EXPECT_TRUE(contains(wrong_unit.err, "warning: --gravity 0,0,-9810 is more than 10 g"))
      << wrong_unit.err;
  const auto warnings = [](const std::string& out) {
    const std::size_t at = out.find("warnings: ");
    return at == std::string::npos ? -1 : std::stoi(out.substr(at + 10));
  };
  EXPECT_EQ(warnings(wrong_unit.out), warnings(check.out) + 1) << wrong_unit.out;

  afhub::testing::ModelFolder folder;
  const auto sag = [&](const std::vector<std::string>& extra) {
    const std::string report = (folder.dir() / "report.json").string();
    std::vector<std::string> args = {"run",     kuka,   "--offline", "--fast",
                                     "--steps", "1000", "--report",  report};
    args.insert(args.end(), extra.begin(), extra.end());
    RunResult result = run_afhub(args, 60s);
    EXPECT_EQ(result.exit_code, 0) << result.err;
    EXPECT_TRUE(contains(result.err, "lowered to")) << result.err;
    const nlohmann::json json = parse_json(read_file(report));
    return std::abs(json.at("joints").at("ambf/env/link1-link2").at("position").get<double>());
  };
  EXPECT_LT(sag({}), 1e-3) << "gravity 0 from the file: the arm stays";
  EXPECT_GT(sag({"--gravity", "0,0,-9.81"}), 0.05) << "--gravity: the arm sags";
}

// Joint gains from outside the model files: `check` lists the joints on AMBF's default
// gains and takes the options as `run` does; bad values and names are errors naming
// the option, before anything runs.
TEST(Cli, GainsFromTheCommandLine) {
  const std::string rcm = AFHUB_EXAMPLE_MODELS "/rcm.yaml";
  RunResult own = run_afhub({"check", rcm});
  EXPECT_EQ(own.exit_code, 0) << own.err;
  EXPECT_TRUE(contains(own.out, "joints on AMBF's default gains")) << own.out;
  EXPECT_TRUE(contains(own.out, "sets theirs): 0")) << own.out;  // the RCM's file gives its own
  RunResult unknown = run_afhub({"check", rcm, "--gains", "x=1,0,0"});
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_TRUE(contains(unknown.err, "--gains: no joint or body is named 'x'")) << unknown.err;
  EXPECT_TRUE(contains(unknown.err, "afhub/rcm/base-yaw_link")) << unknown.err;  // candidates
  for (const std::vector<std::string>& bad :
       std::vector<std::vector<std::string>>{{"--default-gains", "1000,0"},
                                             {"--default-gains", "1000,-1,10"},
                                             {"--default-gains", "nan,0,10"},
                                             {"--default-gains", "1000,0,1e999"},
                                             {"--default-gains", "1e308,0,10"},
                                             {"--gains", "rcm/base=1000,0,x"}}) {
    std::vector<std::string> args = {"run", rcm, "--offline", "--steps", "1"};
    args.insert(args.end(), bad.begin(), bad.end());
    RunResult result = run_afhub(args, 30s);
    EXPECT_EQ(result.exit_code, 1) << bad[1];
    EXPECT_TRUE(contains(result.err, bad[0] + " takes P,I,D: three numbers from 0 to 1e9"))
        << result.err;
  }
  RunResult unnamed = run_afhub({"run", rcm, "--offline", "--steps", "1", "--gains", "1,0,1"}, 30s);
  EXPECT_EQ(unnamed.exit_code, 1);
  EXPECT_TRUE(contains(unnamed.err, "--gains takes NAME=P,I,D")) << unnamed.err;
}

// The ECM's file gives its joints no gains: `check` names them, and none is left on
// AMBF's default with --default-gains, whose P the cap lowers for the light tool link.
TEST(Cli, CheckNamesTheEcmsJointsOnDefaultGains) {
  SKIP_WITHOUT_SHARED_MODELS();
  const std::string ecm = AFHUB_SHARED_MODELS "/descriptions/multi-bodies/robots/blender-ecm.yaml";
  RunResult check = run_afhub({"check", ecm});
  EXPECT_EQ(check.exit_code, 0) << check.err;
  EXPECT_TRUE(contains(check.out, "sets theirs): 4")) << check.out;
  EXPECT_TRUE(contains(check.out, "ambf/env/ecm/baselink-yawlink")) << check.out;
  EXPECT_TRUE(contains(check.out, "blender-ecm.yaml:586:3")) << check.out;
  RunResult given = run_afhub({"check", ecm, "--default-gains", "1000,0,10"});
  EXPECT_EQ(given.exit_code, 0) << given.err;
  EXPECT_TRUE(contains(given.out, "sets theirs): 0")) << given.out;
  EXPECT_TRUE(contains(given.out, "'maininsertionlink-toollink': P 1000 lowered to")) << given.out;
}

TEST(Cli, LookingToolsWithoutAHubFailFastAndSayHowToStartOne) {
  expect_no_hub();
  for (auto args : std::vector<std::vector<std::string>>{
           {"ls"}, {"echo", "base"}, {"status"}, {"cmd", "base", "--force", "0,0,1"}}) {
    RunResult result = run_afhub(args, 5s);
    EXPECT_EQ(result.exit_code, 1) << args[0];
    // At once, not after iceoryx's 60 s wait for a RouDi (a bound no load reaches).
    EXPECT_LT(result.seconds, 10.0) << args[0];
    EXPECT_TRUE(contains(result.err, "no hub is running")) << result.err;
    EXPECT_TRUE(contains(result.err, "afhub hub")) << result.err;
  }
  EXPECT_NE(probe_roudi(), RoudiPresence::kRunning) << "a looking tool started a hub";
}

TEST(Cli, SecondHubIsRefusedAndStopWorks) {
  expect_no_hub();
  ScopedProcess hub(start_test_hub());
  RunResult second = run_afhub({"hub"}, 5s);
  EXPECT_EQ(second.exit_code, 1);
  EXPECT_LT(second.seconds, 10.0);  // at once, not after a wait for the first to go
  EXPECT_TRUE(contains(second.err, "already running")) << second.err;
  EXPECT_TRUE(contains(second.err, "pid " + std::to_string(hub.pid))) << second.err;

  RunResult stop = run_afhub({"hub", "stop"});
  EXPECT_EQ(stop.exit_code, 0) << stop.err;
  EXPECT_EQ(hub.stop(0), 0) << "the hub did not exit 0 on `afhub hub stop`";
  EXPECT_FALSE(running_hub_pid());
}

TEST(Cli, HubStopsCleanlyOnSigint) {
  expect_no_hub();
  ScopedProcess hub(start_test_hub());
  EXPECT_EQ(hub.stop(SIGINT), 0);
}

TEST(Cli, PublishersStartAHubUnlessToldNotTo) {
  expect_no_hub();
  RunResult refused = run_afhub({"synth", "--no-autostart", "--seconds", "0.2"});
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_TRUE(contains(refused.err, "no hub is running")) << refused.err;

  RunResult started = run_afhub({"synth", "--seconds", "0.3"});
  EXPECT_EQ(started.exit_code, 0) << started.err;
  EXPECT_TRUE(contains(started.err, "started one in the background")) << started.err;
  EXPECT_EQ(probe_roudi(), RoudiPresence::kRunning);
  EXPECT_EQ(run_afhub({"hub", "stop"}).exit_code, 0);
  EXPECT_TRUE(wait_until([] { return probe_roudi() != RoudiPresence::kRunning; }, 5s));
}

// iceoryx's lock still held a moment by a hub that is ending (its process outlives its
// own lock by a second, its memory unmapped): a hub started then gave up at once (CI:
// the first hub of a test started right after the last one's `afhub hub stop`). It
// waits up to 5 s for the lock.
TEST(Cli, AHubWaitsForIceoryxsLockAMoment) {
  expect_no_hub();
  ScopedProcess holder = spawn_command({"flock", "/tmp/iox-unique-roudi.lock", "sleep", "1"});
  ASSERT_TRUE(wait_until([] { return flock_held("/tmp/iox-unique-roudi.lock"); }, 5s));
  ScopedProcess hub(start_test_hub());  // fails the test unless it comes up
  ASSERT_GT(hub.pid, 0);
  EXPECT_EQ(hub.stop(), 0);
}

class CliWithBodies : public ::testing::Test {
 protected:
  void SetUp() override {
    expect_no_hub();
    hub_.pid = start_test_hub();
    synth_.pid = spawn_afhub({"synth", "--bodies", "2", "--joints", "3", "--no-autostart"},
                             "/tmp/afhub-test-synth.log");
    ASSERT_TRUE(wait_until([] { return contains(run_afhub({"ls"}).out, "synth/body1"); }, 20s))
        << read_file("/tmp/afhub-test-synth.log");
  }
  void TearDown() override {
    EXPECT_EQ(synth_.stop(), 0);
    EXPECT_EQ(hub_.stop(), 0);
  }
  ScopedProcess hub_{-1}, synth_{-1};
};

TEST_F(CliWithBodies, LsListsBodiesJointsOwnerAndRate) {
  RunResult json = run_afhub({"ls", "--json"});
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const nlohmann::json bodies = parse_json(json.out);
  const nlohmann::json* body0 = find_element(bodies, "body", "synth/body0");
  const nlohmann::json* body1 = find_element(bodies, "body", "synth/body1");
  ASSERT_TRUE(body0 && body1) << json.out;
  EXPECT_EQ(body1->at("joints"), nlohmann::json({"body1-joint0", "body1-joint1", "body1-joint2"}))
      << json.out;
  EXPECT_EQ(body0->at("owner_pid"), synth_.pid) << json.out;
  EXPECT_EQ(body1->at("owner_pid"), synth_.pid) << json.out;
  // The hub measures rates over a second; synth publishes at 1 kHz.
  RunResult ls;
  EXPECT_TRUE(wait_until(
      [&] {
        ls = run_afhub({"ls", "--json"});
        if (ls.exit_code != 0) return false;
        const nlohmann::json listed = parse_json(ls.out);
        const nlohmann::json* body = find_element(listed, "body", "synth/body0");
        return body && body->at("rate_hz").is_number() &&  // null until measured
               std::abs(body->at("rate_hz").get<double>() - 1000.0) < 20.0;
      },
      20s))  // a README-order run (a clone in /tmp beside the demo's hub) took over 5 s
      << ls.out;
}

TEST_F(CliWithBodies, EchoPrintsJsonLines) {
  RunResult echo = run_afhub({"echo", "body1", "--count", "3", "--json"});
  EXPECT_EQ(echo.exit_code, 0) << echo.err;
  // One JSON document a line.
  std::istringstream lines(echo.out);
  int count = 0;
  for (std::string line; std::getline(lines, line); ++count) {
    const nlohmann::json state = parse_json(line);
    EXPECT_EQ(state.at("body"), "synth/body1") << line;
    EXPECT_EQ(state.at("joint_names").at(0), "body1-joint0") << line;
  }
  EXPECT_EQ(count, 3) << echo.out;
}

TEST_F(CliWithBodies, CmdDrivesTheJointsOfABody) {
  ScopedProcess commander =
      spawn_afhub({"cmd", "body0", "--joint-pos", "0.3,-0.2", "--repeat", "200"});
  // synth's joints converge on a position target within a few hundred steps; each look
  // is a new process (a CI run loaded beside a build took over 5 s to see it).
  bool converged = wait_until(
      [] {
        const RunResult echo = run_afhub({"echo", "synth/body0", "-n", "1", "--json"});
        if (echo.exit_code != 0) return false;
        const nlohmann::json positions = parse_json(echo.out).at("joint_positions");
        return positions.size() == 3 && std::abs(positions.at(0).get<double>() - 0.3) < 1e-3 &&
               std::abs(positions.at(1).get<double>() + 0.2) < 1e-3;
      },
      20s);
  EXPECT_TRUE(converged) << run_afhub({"echo", "synth/body0", "-n", "1", "--json"}).out;
  EXPECT_EQ(commander.stop(SIGINT), 0);
}

TEST_F(CliWithBodies, CmdExplainsBadInput) {
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  for (const Case& bad : std::vector<Case>{
           {{"cmd", "nobody", "--force", "1,2,3"}, "no live body is named 'nobody'"},
           {{"cmd", "body", "--force", "1,2,3"}, "no live body"},
           {{"cmd", "body0", "--joint-pos", "1,nan"}, "'nan' is not a finite number"},
           {{"cmd", "body0", "--joint-pos", "1,0x10,2"}, "'0x10' is not a finite number"},
           {{"cmd", "body0", "--joint-pos", "1,2,3,4"}, "has 3 joints"},
           {{"cmd", "body0", "--force", "1,2"}, "--force takes 3 numbers"},
           {{"cmd", "body0", "--pose", "0,0,0,0,0,0", "--force", "1,0,0"}, "two Cartesian modes"},
           {{"cmd", "body0", "--joint-pos", "1", "--joint-vel", "1"}, "give one"},
           {{"cmd", "body0"}, "nothing to command"},
           {{"echo", "nobody"}, "synth/body0"},
       }) {
    RunResult result = run_afhub(bad.args);
    EXPECT_EQ(result.exit_code, 1) << bad.args[1];
    EXPECT_TRUE(contains(result.err, bad.message))
        << "expected '" << bad.message << "' in: " << result.err;
  }
}

TEST_F(CliWithBodies, StatusShowsProcessesAndMempools) {
  // Health comes once a second: wait for one that has seen synth.
  RunResult status;
  nlohmann::json health;
  EXPECT_TRUE(wait_until(
      [&] {
        status = run_afhub({"status", "--json"});
        if (status.exit_code != 0) return false;
        health = parse_json(status.out);
        const std::string synth = "afhub-synth-" + std::to_string(synth_.pid);
        return find_element(health.at("processes"), "name", synth) && health.at("body_count") == 2;
      },
      20s))
      << status.out;
  ASSERT_EQ(status.exit_code, 0) << status.err;
  // Several segments may hold pools of one size: any of them. States are in blocks of
  // slots, whose first comes from the first tier's pool.
  const nlohmann::json& pools = health.at("mempools");
  EXPECT_TRUE(std::any_of(pools.begin(), pools.end(), [](const nlohmann::json& pool) {
    return pool.at("chunk_payload_bytes") ==
           slot_block_pool_bytes(first_slot_block_bytes(body_state_bytes(64)));
  })) << status.out;
  const nlohmann::json* body1 = find_element(health.at("bodies"), "body", "synth/body1");
  ASSERT_NE(body1, nullptr) << status.out;
  EXPECT_TRUE(body1->contains("rate_hz")) << status.out;
}

}  // namespace
}  // namespace afhub::test
