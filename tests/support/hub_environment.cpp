// The hub used by a test binary (see hub_environment.hpp).
#include "hub_environment.hpp"

#include <signal.h>

#include "afhub/hub/hub_presence.hpp"
#include "afhub_process.hpp"

namespace afhub::test {

pid_t start_test_hub() {
  if (probe_roudi() == RoudiPresence::kRunning) {
    ADD_FAILURE() << "a hub (or RouDi) is already running on this machine; the hub tests start "
                     "their own. Stop it with `afhub hub stop` and run the tests again.";
    return -1;
  }
  pid_t hub = spawn_afhub({"hub"}, "/tmp/afhub-test-hub.log");
  bool up = wait_until([] { return probe_roudi() == RoudiPresence::kRunning && running_hub_pid(); },
                       kHubStartWait);
  EXPECT_TRUE(up) << "the test hub did not come up; its log:\n"
                  << read_file("/tmp/afhub-test-hub.log");
  return hub;
}

void HubEnvironment::SetUp() {
  hub_ = start_test_hub();
  ASSERT_GT(hub_, 0);
  connect_to_hub("test", HubPolicy::kRequire);
}

void HubEnvironment::TearDown() {
  if (hub_ > 0) {
    EXPECT_EQ(stop_process(hub_, SIGTERM), 0) << "the hub did not stop cleanly";
  }
  // A client left running would attach to the next binary's hub.
  for (const std::string& child : stop_leftover_children())
    ADD_FAILURE() << "a child process was left running; stopped it: " << child;
}

}  // namespace afhub::test
