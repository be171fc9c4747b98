// main() for tests that run in-process against one hub started for the whole binary.
#include <gtest/gtest.h>

#include "hub_environment.hpp"

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ::testing::AddGlobalTestEnvironment(new afhub::test::HubEnvironment);
  return RUN_ALL_TESTS();
}
