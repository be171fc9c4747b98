// The real AMBF models in ../shared/ambf_models (AFHUB_SHARED_MODELS), read in
// place and never copied into the project. A user's clone has no ../shared: the
// tests that need the corpus then skip, naming the missing directory, and every
// other test runs without it.
#pragma once

#include <filesystem>
#include <string>

namespace afhub::testing {

inline const std::string kSharedModels = AFHUB_SHARED_MODELS;
// Its robots (the KUKA, the ECM, the MTM, ...), each a folder of ADF files.
inline const std::string kMultiBodies = kSharedModels + "/descriptions/multi-bodies/";

inline bool shared_models_present() {
  return std::filesystem::is_directory(kSharedModels);
}

inline std::string shared_models_missing() {
  return "needs the AMBF model corpus, and " + kSharedModels +
         " does not exist (AFHUB_SHARED_MODELS; CI has it)";
}

}  // namespace afhub::testing

// First in a GoogleTest test that reads the corpus: skips it when the corpus is missing.
#define SKIP_WITHOUT_SHARED_MODELS()                             \
  do {                                                           \
    if (!::afhub::testing::shared_models_present())              \
      GTEST_SKIP() << ::afhub::testing::shared_models_missing(); \
  } while (0)
