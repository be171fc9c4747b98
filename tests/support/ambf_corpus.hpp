// The real AMBF models in ../shared/ambf_models, read in place (never copied into
// the project). A user's clone has no ../shared: tests that need the corpus skip
// there, naming the missing folder. CI always has it.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>

// Skips the current test when the corpus folder is missing.
#define AFHUB_REQUIRE_AMBF_CORPUS()                                                             \
  do {                                                                                          \
    if (!std::filesystem::is_directory(AFHUB_SHARED_MODELS))                                    \
      GTEST_SKIP() << "the AMBF corpus is not there: " AFHUB_SHARED_MODELS                      \
                      " is missing (it sits beside the project in the team's checkout and CI)"; \
  } while (false)
