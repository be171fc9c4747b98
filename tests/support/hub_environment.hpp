// A hub for the duration of a test binary: started before the first test, stopped
// (with SIGTERM, expecting exit 0) after the last.
#pragma once

#include <gtest/gtest.h>
#include <sys/types.h>

#include <chrono>

namespace afhub::test {

// How long a test waits for a hub it started to answer: RouDi writes its 150 MB of
// segments at start, which took over 10 s on the loaded 2-core CI machine (a wait for an
// event, not a bound on its speed).
inline constexpr std::chrono::seconds kHubStartWait{30};

// Starts `afhub hub` and waits until it answers; fails the test when it does not
// or when a hub is already running (the tests never touch a user's hub).
pid_t start_test_hub();

class HubEnvironment : public ::testing::Environment {
 public:
  void SetUp() override;
  void TearDown() override;

 private:
  pid_t hub_ = -1;
};

}  // namespace afhub::test
