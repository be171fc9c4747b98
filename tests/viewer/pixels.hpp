// Screenshot checks from the viewer tests: pixels.py beside this file (see there).
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "afhub_process.hpp"

namespace afhub::test {

// `pixels.py args...`: the number it prints (0 after a failure it reports).
inline long pixels(const std::vector<std::string>& args) {
  std::vector<std::string> argv = {"/usr/bin/python3", AFHUB_VIEWER_PIXELS_SCRIPT};
  argv.insert(argv.end(), args.begin(), args.end());
  const RunResult result = run_command(argv);
  EXPECT_EQ(result.exit_code, 0) << result.err;
  return std::atol(result.out.c_str());
}

}  // namespace afhub::test
