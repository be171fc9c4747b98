// A report's line from a printf pattern of up to four numbers.
#pragma once

#include <cstdio>
#include <string>

namespace afhub::bench {

inline std::string format(const char* pattern, double a, double b = 0.0, double c = 0.0,
                          double d = 0.0) {
  char text[256];
  std::snprintf(text, sizeof text, pattern, a, b, c, d);
  return text;
}

}  // namespace afhub::bench
