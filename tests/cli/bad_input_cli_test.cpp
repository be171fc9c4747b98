// `afhub check` and `afhub run` on bad input (issue 13): a clear error and exit 1,
// never a crash, an abort or a run that never ends. Needs no hub: `check` never
// connects and `run` is refused before it would. And `afhub cmd` with values the
// physics refuses (with a hub and the physics of its own).
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include "afhub/shm_layout/limits.hpp"
#include "afhub_process.hpp"
#include "hub_environment.hpp"
#include "model_files.hpp"

namespace afhub::test {
namespace {

namespace fs = std::filesystem;

const std::string kArm = AFHUB_EXAMPLE_MODELS "/arm7.yaml";

// `afhub args...` as an unprivileged user (file modes apply even when the tests
// run as root).
RunResult run_unprivileged(const std::vector<std::string>& args) {
  std::vector<std::string> argv;
  if (geteuid() == 0) argv = {"setpriv", "--reuid", "65534", "--regid", "65534", "--clear-groups"};
  argv.push_back(afhub_executable());
  argv.insert(argv.end(), args.begin(), args.end());
  return run_command(argv);
}

TEST(BadInputCli, ABrokenMeshIsAnErrorForCheckAndRunNotACrash) {
  afhub::testing::ModelFolder folder;
  folder.write("garbage.STL", "this is not a mesh\n");
  const std::string model = folder.write("model.yaml",
                                         "bodies: [BODY a]\nBODY a:\n  name: a\n  mass: 1\n"
                                         "  mesh: garbage.STL\n");
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"check", model}, {"run", model, "--offline", "--steps", "1"}}) {
    RunResult result = run_afhub(args);
    EXPECT_EQ(result.exit_code, 1) << args[0] << ": " << result.err;
    EXPECT_TRUE(
        contains(result.err, "model.yaml:3:3: error: body 'BODY a': its mesh cannot be used"))
        << args[0] << ": " << result.err;
  }
}

// A stopped hub does not answer registration: every new client waited 60 s for it, then
// aborted in iceoryx. Said at once.
TEST(BadInputCli, AStoppedHubIsSaidAtOnce) {
  ScopedProcess hub(start_test_hub());
  ASSERT_EQ(kill(hub.pid, SIGSTOP), 0);
  const RunResult ls = run_afhub({"ls"}, std::chrono::seconds(30));
  ASSERT_EQ(kill(hub.pid, SIGCONT), 0);
  EXPECT_EQ(ls.exit_code, 1) << ls.err;
  EXPECT_TRUE(contains(ls.err, "the hub (pid " + std::to_string(hub.pid) + ") is stopped"))
      << ls.err;
  EXPECT_EQ(run_afhub({"ls"}).exit_code, 0) << "running on, it answers";
}

// `afhub convert` wrote an ADF file naming a mesh that `check` and `run` refuse.
TEST(BadInputCli, ConvertRefusesAMeshCheckWouldRefuse) {
  afhub::testing::ModelFolder folder;
  folder.write("garbage.stl", "this is not a mesh\n");
  const std::string robot = folder.write(
      "robot.urdf",
      "<?xml version=\"1.0\"?>\n<robot name=\"r\">\n  <link name=\"a\">\n    <collision>"
      "<geometry><mesh filename=\"garbage.stl\"/></geometry></collision>\n  </link>\n"
      "</robot>\n");
  const std::string written = (folder.dir() / "robot.yaml").string();
  const RunResult convert = run_afhub({"convert", robot, "-o", written});
  EXPECT_EQ(convert.exit_code, 1) << convert.err;
  EXPECT_TRUE(contains(convert.err, "robot.urdf:3:3: error: ")) << convert.err;
  EXPECT_TRUE(contains(convert.err, "garbage.stl")) << convert.err;
  EXPECT_FALSE(std::filesystem::exists(written)) << "nothing written";
}

// A negative --seconds ran synth and the demo until killed; record's --duration refused it.
TEST(BadInputCli, NegativeSecondsAreRefusedNotForever) {
  for (const std::string command : {"synth", "demo"}) {
    const RunResult result = run_afhub({command, "--seconds", "-1"});
    EXPECT_EQ(result.exit_code, 1) << command << ": " << result.err;
    EXPECT_TRUE(contains(result.err, "--seconds (0: until Ctrl-C) takes seconds from 0"))
        << command << ": " << result.err;
  }
}

// `-o` naming the URDF itself (or a link to it) replaced the robot with its ADF.
TEST(BadInputCli, ConvertRefusesToWriteOverItsOwnInput) {
  afhub::testing::ModelFolder folder;
  const std::string text =
      "<?xml version=\"1.0\"?>\n<robot name=\"r\">\n  <link name=\"a\"/>\n</robot>\n";
  const std::string robot = folder.write("robot.urdf", text);
  const std::string link = (folder.dir() / "link.urdf").string();
  std::filesystem::create_symlink(robot, link);
  for (const std::string& output : {robot, link}) {
    const RunResult convert = run_afhub({"convert", robot, "-o", output});
    EXPECT_EQ(convert.exit_code, 1) << convert.err;
    EXPECT_TRUE(contains(convert.err, "is the URDF file itself")) << convert.err;
  }
  EXPECT_EQ(read_file(robot), text) << "the URDF was overwritten";
}

TEST(BadInputCli, AnUnreadableModelOrADirectoryIsSaidSo) {
  afhub::testing::ModelFolder folder;
  const std::string model = folder.write("locked.yaml", "bodies: []\n");
  fs::permissions(model, fs::perms::none);
  fs::permissions(folder.dir(), fs::perms::all);
  for (const std::string command : {"check", "run"}) {
    std::vector<std::string> args = {command, model};
    if (command == "run") args.push_back("--offline");
    const RunResult unprivileged = run_unprivileged(args);
    const std::string& err = unprivileged.err;
    EXPECT_EQ(unprivileged.exit_code, 1) << command << ": " << err;
    EXPECT_TRUE(contains(err, "locked.yaml: error: permission denied")) << command << ": " << err;
    EXPECT_FALSE(contains(err, "terminate")) << err;

    RunResult directory = run_afhub({command, folder.dir().string(), "--offline"});
    if (command == "check") directory = run_afhub({command, folder.dir().string()});
    EXPECT_EQ(directory.exit_code, 1) << directory.err;
    EXPECT_TRUE(contains(directory.err, "this is a directory")) << directory.err;
  }
  // A message located in its file says "error" once (it said "error: /dev/zero: error:").
  const RunResult device = run_afhub({"device", "run", "virtual", "--trajectory", "/dev/zero"});
  EXPECT_EQ(device.exit_code, 1) << device.err;
  EXPECT_TRUE(contains(device.err, "afhub device: /dev/zero: error: this is not a regular file"))
      << device.err;
}

// Two models loaded at one place were pushed apart at the first step, hard enough to blow
// one up (the MTM over the SUJ), with nothing said at load. The overlap is said, located,
// with what mends it: --at, or for files a joint holds together, that joint; placed apart,
// nothing is said.
TEST(BadInputCli, ModelsLoadedOverlappingAreSaidWithWhatMendsIt) {
  const RunResult twice = run_afhub({"check", kArm, kArm});
  EXPECT_EQ(twice.exit_code, 0) << twice.err;
  EXPECT_TRUE(contains(twice.err, kArm +
                                      ":54:3: warning: body 'afhub/arm/base' overlaps body "
                                      "'afhub/arm/base1' of another loaded file (" +
                                      kArm + ":54:3) by "))
      << twice.err;
  EXPECT_TRUE(contains(twice.err, "place one file elsewhere with --at FILE=x,y,z")) << twice.err;
  EXPECT_TRUE(contains(twice.err, "more pairs of bodies of different loaded files overlap"))
      << twice.err;
  const RunResult apart = run_afhub({"check", kArm, kArm, "--at", kArm + "=0,3,0"});
  EXPECT_EQ(apart.exit_code, 0) << apart.err;
  EXPECT_FALSE(contains(apart.err, "overlap")) << apart.err;
  // One robot's own links overlap at their joints: no warning.
  const RunResult alone = run_afhub({"check", kArm});
  EXPECT_FALSE(contains(alone.err, "overlap")) << alone.err;
  // A probe on the arm's base, in a file of its own, jointed to it and reaching into its
  // first links: moving its file would not part them.
  afhub::testing::ModelFolder folder;
  const std::string probe = folder.write(
      "probe.yaml",
      "bodies: [BODY probe]\njoints: [JOINT arm-probe]\nBODY probe:\n  name: probe\n"
      "  mass: 0.5\n  location: {position: {x: 0, y: 0, z: 0.3}, orientation: {r: 0, p: 0, y: "
      "0}}\n  collision shape: BOX\n  collision geometry: {x: 0.2, y: 0.2, z: 0.2}\n"
      "JOINT arm-probe:\n  name: arm-probe\n  parent: /afhub/arm/BODY base\n"
      "  child: BODY probe\n  parent pivot: {x: 0, y: 0, z: 0}\n"
      "  child pivot: {x: 0, y: 0, z: 0}\n  parent axis: {x: 0, y: 0, z: 1}\n"
      "  child axis: {x: 0, y: 0, z: 1}\n  type: fixed\n");
  const RunResult joined = run_afhub({"check", kArm, probe});
  EXPECT_EQ(joined.exit_code, 0) << joined.err;
  EXPECT_TRUE(contains(joined.err, "body 'ambf/env/probe' overlaps body 'afhub/arm/link1'"))
      << joined.err;
  EXPECT_TRUE(contains(joined.err,
                       "the joint 'arm-probe' (" + probe + ":10:3) holds the two files together"))
      << joined.err;
  EXPECT_FALSE(contains(joined.err, "--at FILE")) << joined.err;
  EXPECT_FALSE(contains(joined.err, "overlaps body 'afhub/arm/base'")) << "jointed: no contact";
}

TEST(BadInputCli, CheckRefusesWhatRunWouldRefuse) {
  afhub::testing::ModelFolder folder;
  const std::size_t bodies = kMaxBodies + 50;
  std::string text = "bodies: [";
  for (std::size_t i = 0; i < bodies; ++i) text += (i ? ", BODY b" : "BODY b") + std::to_string(i);
  text += "]\n";
  for (std::size_t i = 0; i < bodies; ++i)
    text += "BODY b" + std::to_string(i) + ":\n  name: b" + std::to_string(i) + "\n  mass: 1\n";
  RunResult check = run_afhub({"check", folder.write("many.yaml", text)});
  EXPECT_EQ(check.exit_code, 1) << check.out;
  EXPECT_TRUE(contains(check.err, "is published body number " + std::to_string(kMaxBodies + 1) +
                                      "; the hub holds at most " + std::to_string(kMaxBodies)))
      << check.err;
}

// The costliest files within every bound (size, nodes, depth, bodies): `afhub check`
// answers each within 2 GB of address space, with its verdict, never out of memory. Its
// time is printed (a figure for docs/simulating.md, not a bound: this machine is shared).
TEST(BadInputCli, TheCostliestModelFilesWithinTheBoundsCheckWithin2GB) {
#if defined(AFHUB_SANITIZED)
  // ASan reserves terabytes of address space for itself, so no bound can apply here; the
  // same files' code paths run under the sanitizers in smaller files (adf_fuzz).
  GTEST_SKIP() << "a bound on memory: checked in the release build, not under the sanitizers";
#endif
  afhub::testing::ModelFolder folder;
  std::string junk;  // top-level blocks no body names: lookups among many keys
  for (int i = 0; i < 300000; ++i) junk += "k" + std::to_string(1000000 + i) + ": 0\n";
  std::string flat = "bodies: [0";  // nodes up to the bound, each a few bytes
  for (std::size_t i = 2; i < kMaxYamlNodes - 8; ++i) flat += ",0";
  flat += "]\n";
  const std::vector<std::pair<std::string, std::string>> files = {
      {"bodies.yaml",
       junk + afhub::testing::passive_spheres_at_origin(static_cast<int>(kMaxModelBodies))},
      {"flat.yaml", flat},
      {"scalar.yaml", "name: " + std::string(kMaxYamlFileBytes - 64, 'x') + "\n"}};
  for (const auto& [name, text] : files) {
    ASSERT_LE(text.size(), kMaxYamlFileBytes) << name;
    const std::string path = folder.write(name, text);
    const RunResult check = run_command(
        {"prlimit", "--as=" + std::to_string(2ULL << 30), "--", afhub_executable(), "check", path},
        std::chrono::seconds(120));
    std::printf("afhub check %s (%zu bytes): exit %d in %.2f s\n", name.c_str(), text.size(),
                check.exit_code, check.seconds);
    EXPECT_TRUE(check.exit_code == 0 || check.exit_code == 1) << name << ": " << check.err;
    EXPECT_FALSE(contains(check.err, "bad_alloc") || contains(check.err, "memory")) << check.err;
    if (check.exit_code == 1) {
      EXPECT_TRUE(contains(check.err, name + ":")) << check.err;
    }
  }
}

TEST(BadInputCli, NumericOptionsOutOfRangeAreRefused) {
  struct Case {
    std::vector<std::string> args;
    std::string option;
  };
  const std::vector<Case> cases = {
      {{"run", kArm, "--offline", "--steps", "-1"}, "--steps"},
      {{"run", kArm, "--offline", "--steps", "18446744073709551616"}, "--steps"},
      {{"run", kArm, "--offline", "--steps", "0x10"}, "--steps"},
      {{"run", kArm, "--offline", "--wait-for", "-1", "--lockstep"}, "--wait-for"},
      {{"run", kArm, "--offline", "--wait-timeout", "inf"}, "--wait-timeout"},
      {{"run", kArm, "--offline", "--cpu", "99999999999"}, "--cpu"},
      {{"ctl", "hold", "arm", "--cycles", "-1"}, "--cycles"},
      {{"echo", "arm", "--count", "-5"}, "--count"},
      {{"synth", "--bodies", "-1"}, "--bodies"},
      {{"world", "step", "4294967296"}, "N"},
      // Periods and spans past an int64 of nanoseconds came out negative: a loop at
      // 1e-10 Hz spun at full speed, a 1e10 s recording ended at once.
      {{"cmd", "arm", "--joint", "0=0.1", "--rate", "1e-10"}, "--rate"},
      {{"ctl", "hold", "arm", "--rate", "1e-12"}, "--rate"},
      {{"ctl", "sine", "arm", "--period", "1e-308"}, "--period"},
      {{"synth", "--rate", "1e-12"}, "--rate"},
      {{"echo", "arm", "-n", "5", "--timeout", "nan"}, "--timeout"},
      {{"echo", "arm", "--rate", "1e-308"}, "--rate"},
      {{"record", "--duration", "1e10"}, "--duration"},
      // civetweb read 999.1.1.1 as 231.1.1.1 and listened there.
      {{"view", "--bind", "999.1.1.1"}, "--bind"},
      // Debian's civetweb has no IPv6: said, not "the port is in use".
      {{"view", "--bind", "::1"}, "listens on IPv4 only"},
      // Files that never end were read until memory ran out.
      {{"hub", "--dry-run", "--mempools", "/dev/zero"}, "not a regular file"},
      {{"ctl", "track", "arm", "/dev/zero"}, "not a regular file"},
      // Every body went NaN each step.
      {{"run", kArm, "--offline", "--gravity", "0,0,-1e308"}, "--gravity"},
      {{"run", kArm, "--offline", "--default-gains", "1e308,0,0"}, "--default-gains"},
      // -1 is the option's "unset" default, and was taken when written.
      {{"run", kArm, "--offline", "--cpu-wake-latency", "-1"}, "--cpu-wake-latency"},
      {{"bridge", "dds", "--check", "--export", "--cpu-wake-latency", "-1"}, "--cpu-wake-latency"},
  };
  for (const Case& c : cases) {
    RunResult result = run_afhub(c.args, std::chrono::seconds(10));
    std::string line;
    for (const auto& arg : c.args) line += arg + " ";
    EXPECT_NE(result.exit_code, 0) << line << "was accepted";
    EXPECT_NE(result.exit_code, -1) << line << "ran on";
    EXPECT_LT(result.exit_code, 128) << line << "crashed: " << result.err;
    EXPECT_TRUE(contains(result.err + result.out, c.option))
        << line << "did not name the option: " << result.err;
  }
  // In range, they are taken.
  RunResult ten = run_afhub({"run", kArm, "--offline", "--fast", "--steps", "10"});
  EXPECT_EQ(ten.exit_code, 0) << ten.err;
}

// A short step log went to the stream's buffer and was lost unsaid when the disk was
// full: its close is checked.
TEST(BadInputCli, ALogOrReportThatCannotBeWrittenIsAnError) {
  for (const std::string option : {"--step-log", "--report"}) {
    const RunResult full =
        run_afhub({"run", kArm, "--offline", "--fast", "--steps", "200", option, "/dev/full"},
                  std::chrono::seconds(60));
    EXPECT_EQ(full.exit_code, 1) << option << ": " << full.err;
    EXPECT_TRUE(contains(full.err, "cannot write the")) << option << ": " << full.err;
  }
}

// `cmd arm/base --joint base-link1=1e9` used to say "commanding" and keep sending while
// the physics refused every command on its own stderr: cmd reads the refusal back from
// the body's state and stops with the physics' reason.
TEST(BadInputCli, CmdStopsWithThePhysicsRefusalOfItsCommand) {
  afhub::testing::ModelFolder folder;
  const std::string log = (folder.dir() / "run.log").string();
  ScopedProcess hub(start_test_hub());
  ASSERT_GT(hub.pid, 0);
  ScopedProcess physics(spawn_afhub({"run", kArm, "--no-autostart"}, log));
  ASSERT_TRUE(wait_until(
      [] {
        return run_afhub({"echo", "arm/base", "-n", "1"}).exit_code == 0;
      },
      std::chrono::seconds(20)))
      << read_file(log);
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"cmd", "arm/base", "--joint", "base-link1=1e9"},
        {"cmd", "arm/base", "--joint", "base-link1=1e9", "--once"},
        {"cmd", "arm/base", "--joint-effort", "1e12", "--others", "release"}}) {
    const RunResult result = run_afhub(args, std::chrono::seconds(10));
    EXPECT_EQ(result.exit_code, 1) << args.back() << ": " << result.err;
    EXPECT_TRUE(contains(result.err,
                         "the physics refused the command for afhub/arm/base: joint 0 "
                         "(base-link1)"))
        << result.err;
    EXPECT_TRUE(contains(result.err, "is beyond its bound of")) << result.err;
  }
  // A command within the bounds is taken.
  const RunResult taken = run_afhub({"cmd", "arm/base", "--joint", "base-link1=0.1", "--once"});
  EXPECT_EQ(taken.exit_code, 0) << taken.err;
  EXPECT_FALSE(contains(read_file(log), "cannot reach")) << read_file(log);
  // A target past the joint's limits (degrees typed) is taken, driven to the nearest limit,
  // and said once per sender: it was clamped without a word. One sender at 100 Hz for a
  // second, then another once.
  ScopedProcess repeating(spawn_afhub({"cmd", "arm/base", "--joint", "base-link1=90"},
                                      (folder.dir() / "repeating.log").string()));
  EXPECT_TRUE(wait_until([&] { return contains(read_file(log), "cannot reach"); },
                         std::chrono::seconds(5)));
  std::this_thread::sleep_for(std::chrono::seconds(1));  // a second line would be out by then
  EXPECT_EQ(repeating.stop(SIGINT), 0);
  std::string physics_said = read_file(log);
  EXPECT_EQ(physics_said.find("cannot reach"), physics_said.rfind("cannot reach")) << physics_said;
  const RunResult degrees = run_afhub({"cmd", "arm/base", "--joint", "base-link1=90", "--once"});
  EXPECT_EQ(degrees.exit_code, 0) << degrees.err;
  EXPECT_TRUE(wait_until(
      [&] {
        const std::string now = read_file(log);
        return now.find("cannot reach") != now.rfind("cannot reach");
      },
      std::chrono::seconds(5)))
      << read_file(log);
  physics_said = read_file(log);
  EXPECT_TRUE(contains(physics_said,
                       "afhub run: a command for afhub/arm/base holds a target it cannot reach: "
                       "joint 0 (base-link1): position target 90 is outside its limits [-2.96, "
                       "2.96] (rad, not degrees), so it is driven to the nearest"))
      << physics_said;
  // A device named is refused at once: its driver reads no body command, and cmd waited
  // 5 s to say that no physics took it.
  ScopedProcess driver(spawn_afhub({"device", "run", "virtual", "--name", "grip"},
                                   (folder.dir() / "driver.log").string()));
  ASSERT_TRUE(wait_until([] { return contains(run_afhub({"ls"}).out, "device/grip"); },
                         std::chrono::seconds(20)))
      << read_file((folder.dir() / "driver.log").string());
  const RunResult device = run_afhub({"cmd", "grip", "--force", "1,0,0", "--once"});
  EXPECT_EQ(device.exit_code, 1) << device.err;
  EXPECT_TRUE(contains(device.err, "device/grip is a device, not a body")) << device.err;
  EXPECT_TRUE(contains(device.err, "`afhub device force grip --force x,y,z`")) << device.err;

  // A controller whose every command is refused says so (it printed only "commanding"),
  // at most once a second.
  const RunResult sine =
      run_afhub({"ctl", "sine", "arm/base", "--amplitude", "1e308", "--cycles", "2500"},
                std::chrono::seconds(60));
  EXPECT_EQ(sine.exit_code, 0) << sine.err;
  EXPECT_TRUE(contains(sine.err, "afhub ctl sine: the physics refused ")) << sine.err;
  EXPECT_TRUE(contains(sine.err, " of this controller (nothing of")) << sine.err;
  EXPECT_TRUE(contains(sine.err, "applied), the last: joint 0 (base-link1) position")) << sine.err;
  EXPECT_TRUE(contains(sine.err, "is beyond its bound of")) << sine.err;
  std::size_t said = 0;
  for (std::size_t at = 0; (at = sine.err.find("the physics refused", at)) != std::string::npos;
       ++at)
    ++said;
  EXPECT_GE(said, 2u) << sine.err;  // the first, then the count a second later
  EXPECT_LE(said, 4u) << sine.err;
  // Joints the body does not have are refused before the first command.
  const RunResult joints =
      run_afhub({"ctl", "sine", "arm/base", "--joints", "99"}, std::chrono::seconds(30));
  EXPECT_EQ(joints.exit_code, 1) << joints.err;
  EXPECT_TRUE(contains(joints.err, "--joints needs 100 joints, and afhub/arm/base has 7"))
      << joints.err;
  const std::string trajectory = (folder.dir() / "eight.csv").string();
  std::ofstream(trajectory) << "0,0,0,0,0,0,0,0,0\n1,0,0,0,0,0,0,0,0.1\n";
  const RunResult track =
      run_afhub({"ctl", "track", "arm/base", trajectory}, std::chrono::seconds(30));
  EXPECT_EQ(track.exit_code, 1) << track.err;
  EXPECT_TRUE(contains(track.err, "needs 8 joints, and afhub/arm/base has 7")) << track.err;
  EXPECT_EQ(physics.stop(), 0) << read_file(log);
  EXPECT_EQ(hub.stop(), 0);
}

}  // namespace
}  // namespace afhub::test
