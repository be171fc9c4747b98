// Bounds that need the loops to keep their 1 kHz periods.
#pragma once

#include <gtest/gtest.h>

// The sanitize build (Debug, ASan and UBSan: several times slower) cannot keep a
// physics, a driver and teleop at 1 kHz on a loaded 2-core machine. There a test runs
// its scenario up to this point, for the sanitizers and for the checks before it, prints
// its figures, and ends skipped, saying so; the release build, which `run.sh test` runs
// first, checks the bounds after it.
#if defined(AFHUB_SANITIZED)
#define SKIP_REAL_TIME_BOUNDS_IN_SANITIZED_BUILD() \
  GTEST_SKIP() << "real-time bounds: checked in the release build, not under the sanitizers"
#else
#define SKIP_REAL_TIME_BOUNDS_IN_SANITIZED_BUILD() static_cast<void>(0)
#endif
