// main() for tests that manage hubs and processes themselves. After the last
// test, no hub and no child may be left running: one left behind would break the
// next binary.
#include <gtest/gtest.h>
#include <signal.h>

#include "afhub/hub/hub_presence.hpp"
#include "afhub_process.hpp"

namespace {

class NoHubLeftBehind : public ::testing::Environment {
 public:
  void TearDown() override {
    if (auto pid = afhub::running_hub_pid()) {
      std::string command = afhub::test::read_file("/proc/" + std::to_string(*pid) + "/cmdline");
      for (char& c : command) c = c ? c : ' ';
      ADD_FAILURE() << "a hub (pid " << *pid << ": " << command
                    << ") was left running; stopping it";
      afhub::test::run_afhub({"hub", "stop", "--force"});
    }
    for (const std::string& child : afhub::test::stop_leftover_children())
      ADD_FAILURE() << "a child process was left running; stopped it: " << child;
  }
};

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ::testing::AddGlobalTestEnvironment(new NoHubLeftBehind);
  return RUN_ALL_TESTS();
}
