// `afhub check` and `afhub run` on bad input (issue 13): a clear error and exit 1,
// never a crash, an abort or a run that never ends. Needs no hub: `check` never
// connects and `run` is refused before it would.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "afhub/shm_layout/limits.hpp"
#include "afhub_process.hpp"
#include "model_files.hpp"

namespace afhub::test {
namespace {

namespace fs = std::filesystem;

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

const std::string kArm = AFHUB_EXAMPLE_MODELS "/arm7.yaml";

// `afhub args...` as an unprivileged user (file modes apply even when the tests
// run as root); returns its exit code, and its stderr in `err`.
int run_unprivileged(const std::vector<std::string>& args, const std::string& err_path,
                     std::string& err) {
  const pid_t child = ::fork();
  if (child == 0) {
    const int fd = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0666);
    if (fd < 0 || ::dup2(fd, STDERR_FILENO) < 0) ::_exit(90);
    if (::geteuid() == 0 && (::setgid(65534) != 0 || ::setuid(65534) != 0)) ::_exit(91);
    std::vector<char*> argv;
    std::string exe = afhub_executable();
    argv.push_back(exe.data());
    for (const auto& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
    argv.push_back(nullptr);
    ::execv(exe.c_str(), argv.data());
    ::_exit(127);
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  err = read_file(err_path);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
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

TEST(BadInputCli, AnUnreadableModelOrADirectoryIsSaidSo) {
  afhub::testing::ModelFolder folder;
  const std::string model = folder.write("locked.yaml", "bodies: []\n");
  fs::permissions(model, fs::perms::none);
  fs::permissions(folder.dir(), fs::perms::all);
  for (const std::string command : {"check", "run"}) {
    std::string err;
    std::vector<std::string> args = {command, model};
    if (command == "run") args.push_back("--offline");
    const int code = run_unprivileged(args, (folder.dir() / "err.txt").string(), err);
    EXPECT_EQ(code, 1) << command << ": " << err;
    EXPECT_TRUE(contains(err, "locked.yaml: error: permission denied")) << command << ": " << err;
    EXPECT_FALSE(contains(err, "terminate")) << err;

    RunResult directory = run_afhub({command, folder.dir().string(), "--offline"});
    if (command == "check") directory = run_afhub({command, folder.dir().string()});
    EXPECT_EQ(directory.exit_code, 1) << directory.err;
    EXPECT_TRUE(contains(directory.err, "this is a directory")) << directory.err;
  }
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

}  // namespace
}  // namespace afhub::test
