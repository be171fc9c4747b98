// Liveness is decided by whether a process exists, in whatever pid namespace it runs
// (a container, `unshare --pid`): by the flock on its iceoryx runtime's lock, which the
// kernel frees when the process dies. Its pid alone says nothing across namespaces: a
// client in a child namespace may be pid 1 there, and the hub's pid means nothing to a
// client outside its namespace.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <string>
#include <thread>

#include "afhub/hub/hub_files.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub_process.hpp"
#include "hub_environment.hpp"

namespace afhub::test {
namespace {

using namespace std::chrono_literals;

const std::string kModel = std::string(AFHUB_EXAMPLE_MODELS) + "/arm7.yaml";
// A process in a pid namespace of its own, with its own /proc (iceoryx names its
// threads through /proc/self), killed with the unshare that started it.
const std::vector<std::string> kOwnPidNamespace = {"unshare", "--pid", "--fork", "--mount-proc",
                                                   "--kill-child"};

bool running(pid_t pid) {
  return waitpid(pid, nullptr, WNOHANG) == 0;
}

class PidNamespaceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (geteuid() != 0) GTEST_SKIP() << "needs root, to make pid namespaces with unshare";
    if (run_afhub({"hub", "stop", "--force"}).exit_code != 0)
      FAIL() << "a hub could not be stopped";
  }
  bool hub_up() {
    return wait_until([] { return probe_roudi() == RoudiPresence::kRunning && running_hub(); },
                      kHubStartWait);
  }
  const std::string hub_log_ = "/tmp/afhub-pidns-hub.log";
};

// A hub in its own pid namespace sees none of its clients' pids: it must keep them all
// the same, and `afhub hub stop` outside must still find and stop it.
TEST_F(PidNamespaceTest, HubInItsOwnPidNamespaceKeepsItsClients) {
  ScopedProcess hub = spawn_wrapped_afhub(kOwnPidNamespace, {"hub"}, hub_log_);
  ASSERT_TRUE(hub_up()) << read_file(hub_log_);
  ScopedProcess physics =
      spawn_afhub({"run", kModel, "--no-autostart"}, "/tmp/afhub-pidns-run.log");
  ScopedProcess hold = spawn_afhub({"ctl", "hold", "arm/base"}, "/tmp/afhub-pidns-ctl.log");
  ASSERT_TRUE(wait_until([] { return contains(run_afhub({"ls"}).out, "arm/base"); }, 10s))
      << read_file(hub_log_);
  std::this_thread::sleep_for(2s);  // 100 of the hub's liveness rounds

  // Outside the hub's pid namespace, a client's name says its own.
  const std::string status = run_afhub({"status"}).out;
  const std::string here = "-ns" + std::to_string(own_pid_namespace()) + "-";
  EXPECT_TRUE(contains(status, "afhub-ctl" + here + std::to_string(hold.pid))) << status;
  EXPECT_TRUE(contains(status, "afhub-physics" + here + std::to_string(physics.pid))) << status;
  EXPECT_TRUE(running(hold.pid) && running(physics.pid));
  EXPECT_FALSE(contains(read_file(hub_log_), "is gone")) << read_file(hub_log_);

  // The hub is the lock's holder here, whatever pid it has in its own namespace.
  const RunResult stop = run_afhub({"hub", "stop", "--force"});
  EXPECT_EQ(stop.exit_code, 0) << stop.err;
  EXPECT_TRUE(contains(stop.err, "stopped the hub")) << stop.err;
  EXPECT_EQ(wait_for_exit(hub, kStopTimeout), 0) << read_file(hub_log_);
}

// A client in a child pid namespace is pid 1 there, a pid that always exists for the
// hub: killed, it must be cleaned up all the same. (Its name says its namespace:
// "afhub-ctl-ns<inode>-1".)
TEST_F(PidNamespaceTest, KilledClientInAChildPidNamespaceIsCleanedUp) {
  ScopedProcess hub = spawn_afhub({"hub"}, hub_log_);
  ASSERT_TRUE(hub_up()) << read_file(hub_log_);
  ScopedProcess physics =
      spawn_afhub({"run", kModel, "--no-autostart"}, "/tmp/afhub-pidns-run.log");
  ScopedProcess hold = spawn_wrapped_afhub(kOwnPidNamespace, {"ctl", "hold", "arm/base"},
                                           "/tmp/afhub-pidns-ctl.log");
  const auto listed = [] {
    const std::string status = run_afhub({"status"}).out;
    return contains(status, "afhub-ctl-ns") && contains(status, "-1 ");
  };
  ASSERT_TRUE(wait_until(listed, 10s))
      << run_afhub({"status"}).out << read_file("/tmp/afhub-pidns-ctl.log");

  kill(hold.pid, SIGKILL);  // and, through --kill-child, the controller in it
  waitpid(hold.pid, nullptr, 0);
  hold.pid = -1;
  EXPECT_TRUE(wait_until([&] { return contains(read_file(hub_log_), "-1 (pid 1) is gone"); }, 2s))
      << read_file(hub_log_);
  EXPECT_TRUE(wait_until([&] { return !listed(); }, 5s)) << run_afhub({"status"}).out;
  EXPECT_TRUE(running(physics.pid));
  EXPECT_EQ(physics.stop(), 0);
  EXPECT_EQ(hub.stop(), 0);
}

// Two physics that are each pid 1 in a pid namespace of their own (two containers'
// entry points) run on one hub: the second was refused by iceoryx, both named
// afhub-physics-1, and crashed.
TEST_F(PidNamespaceTest, TwoPid1ProcessesOfOwnNamespacesShareTheHub) {
  ScopedProcess hub = spawn_afhub({"hub"}, hub_log_);
  ASSERT_TRUE(hub_up()) << read_file(hub_log_);
  ScopedProcess a =
      spawn_wrapped_afhub(kOwnPidNamespace, {"run", kModel, "--namespace", "a", "--no-autostart"},
                          "/tmp/afhub-pidns-a.log");
  ScopedProcess b =
      spawn_wrapped_afhub(kOwnPidNamespace, {"run", kModel, "--namespace", "b", "--no-autostart"},
                          "/tmp/afhub-pidns-b.log");
  EXPECT_TRUE(wait_until(
      [] {
        const std::string ls = run_afhub({"ls"}).out;
        return contains(ls, "a/afhub/arm/base") && contains(ls, "b/afhub/arm/base");
      },
      20s))
      << run_afhub({"ls"}).out << read_file("/tmp/afhub-pidns-a.log")
      << read_file("/tmp/afhub-pidns-b.log");
  EXPECT_TRUE(running(a.pid) && running(b.pid))
      << read_file("/tmp/afhub-pidns-a.log") << read_file("/tmp/afhub-pidns-b.log");
  for (ScopedProcess* physics : {&a, &b}) {  // unshare passes on no SIGTERM: --kill-child
    kill(physics->pid, SIGKILL);
    waitpid(physics->pid, nullptr, 0);
    physics->pid = -1;
  }
  EXPECT_EQ(hub.stop(), 0);
}

// `afhub hub stop` signals the process that holds the hub's lock, never a pid read
// from a file: a pid written into the identity file is not signalled.
TEST_F(PidNamespaceTest, HubStopSignalsTheLockHolderOnly) {
  ScopedProcess hub = spawn_afhub({"hub"}, hub_log_);
  ASSERT_TRUE(hub_up()) << read_file(hub_log_);
  ScopedProcess bystander = spawn_command({"sleep", "30"});
  std::ofstream(hub_identity_path(hub_directory())) << bystander.pid << " 42\n";

  const RunResult stop = run_afhub({"hub", "stop"});
  EXPECT_EQ(stop.exit_code, 0) << stop.err;
  EXPECT_TRUE(contains(stop.err, "stopped the hub (pid " + std::to_string(hub.pid) + ")"))
      << stop.err;
  EXPECT_EQ(wait_for_exit(hub, 5s), 0);
  EXPECT_TRUE(running(bystander.pid));
}

}  // namespace
}  // namespace afhub::test
