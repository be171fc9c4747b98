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

// A wait (for the hub, a body, a device) that Ctrl-C or SIGTERM ended: the user's stop,
// not a failure, so the command says what it waited for and ends with 0.
class Stopped : public Error {
 public:
  explicit Stopped(const std::string& message) : Error(message) {}
};

}  // namespace afhub
