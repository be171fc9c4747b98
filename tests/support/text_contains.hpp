// The tests' one substring check: whether an output or an error message says something.
#pragma once

#include <string>

namespace afhub::test {

inline bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace afhub::test
