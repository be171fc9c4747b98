// What a model file may cost to read (shm_layout/limits.hpp): a file past
// kMaxYamlFileBytes, kMaxYamlNodes or kMaxYamlDepth, or one whose aliases repeat
// past kMaxYamlNodes or contain themselves, is refused with the limit named and
// the place it is passed, before yaml-cpp builds its tree (a 50 MB file of 25
// million values took 11 GB and 49 s to build).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "afhub/physics/adf_loader.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/limits.hpp"
#include "model_files.hpp"
#include "text_contains.hpp"

namespace afhub::physics {
namespace {

namespace fs = std::filesystem;

using afhub::test::contains;

class ModelFileCost : public ::testing::Test {
 protected:
  // The error of loading `text` as `name` ("" if none).
  std::string error_of(const std::string& name, const std::string& text) {
    try {
      load_adf_files({folder_.write(name, text)});
    } catch (const Error& error) {
      return error.what();
    }
    return "";
  }
  testing::ModelFolder folder_;
};

TEST_F(ModelFileCost, AFileLargerThanTheBoundIsRefusedBeforeItIsRead) {
  const std::string path = folder_.write("huge.yaml", "");
  fs::resize_file(path, 50u << 20);  // sparse: 50 MB on paper
  try {
    load_adf_files({path});
    FAIL() << "a 50 MB model loaded";
  } catch (const Error& error) {
    EXPECT_TRUE(contains(error.what(), "huge.yaml: error: the file is 50 MB, larger than the " +
                                           std::to_string(kMaxYamlFileBytes >> 20) + " MB"))
        << error.what();
  }
}

TEST_F(ModelFileCost, TooManyNodesAreRefusedAtTheFirstOnePastTheBound) {
  // Under the byte bound: "values:" then one value a line, the root map, its key and
  // the list being the first three nodes.
  std::string text = "values:\n";
  for (std::size_t i = 0; i < kMaxYamlNodes; ++i) text += "- 0\n";
  ASSERT_LT(text.size(), kMaxYamlFileBytes);
  const std::string message = error_of("many.yaml", text);
  // Node kMaxYamlNodes + 1 is value kMaxYamlNodes - 2, on the line after it.
  EXPECT_TRUE(contains(message, "many.yaml:" + std::to_string(kMaxYamlNodes - 1) +
                                    ":3: error: the file has more than " +
                                    std::to_string(kMaxYamlNodes) + " values, lists and maps"))
      << message;
  EXPECT_TRUE(contains(message, "(kMaxYamlNodes)")) << message;
}

TEST_F(ModelFileCost, NestingDeeperThanTheBoundIsRefusedWhereItIsPassed) {
  const std::string text = "a: " + std::string(100, '[') + std::string(100, ']') + "\n";
  const std::string message = error_of("deep.yaml", text);
  // The root map is level 1: the 64th '[' (column 3 + 64) opens level 65.
  EXPECT_TRUE(contains(message, "deep.yaml:1:" + std::to_string(3 + kMaxYamlDepth) +
                                    ": error: lists and maps nest more than " +
                                    std::to_string(kMaxYamlDepth) + " deep here"))
      << message;
  EXPECT_TRUE(contains(message, "(kMaxYamlDepth)")) << message;
}

TEST_F(ModelFileCost, AliasesCountTheNodesTheyRepeat) {
  // Each level repeats the one before ten times: 11, 111, ... 1111111 nodes, in 300 bytes.
  std::string text = "l0: &l0 [x, x, x, x, x, x, x, x, x, x]\n";
  for (int level = 1; level <= 5; ++level) {
    const std::string before = "*l" + std::to_string(level - 1);
    text += "l" + std::to_string(level) + ": &l" + std::to_string(level) + " [";
    for (int i = 0; i < 10; ++i) text += (i ? ", " : "") + before;
    text += "]\n";
  }
  const std::string message = error_of("laughs.yaml", text);
  EXPECT_TRUE(contains(message, "laughs.yaml:6:")) << message;
  EXPECT_TRUE(contains(message, "more than " + std::to_string(kMaxYamlNodes) + " values"))
      << message;
}

TEST_F(ModelFileCost, AnAliasInsideTheNodeItNamesIsRefused) {
  const std::string message = error_of("loop.yaml", "bodies: []\nloop: &loop [1, *loop]\n");
  EXPECT_TRUE(contains(message,
                       "loop.yaml:2:17: error: this alias names a list or map that "
                       "contains it"))
      << message;
}

TEST_F(ModelFileCost, FilesWithinTheBoundsLoad) {
  std::string text = "bodies: []\n";
  text += "deep: " + std::string(kMaxYamlDepth - 1, '[') + std::string(kMaxYamlDepth - 1, ']');
  text += "\nl0: &l0 [x, x]\nl1: [*l0, *l0]\n";
  EXPECT_EQ(error_of("fits.yaml", text), "");
}

}  // namespace
}  // namespace afhub::physics
