// The error type of every afhub layer's set-up paths. Real-time paths never throw; set-up
// (opening channels, connecting to the hub) throws Error with a message that says
// what is wrong and what to do.
#pragma once

#include <stdexcept>
#include <string>

namespace afhub {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace afhub
