// --wait SECONDS: how long a process started together with the hub and what it uses
// (a launch script's order at its worst) waits for them, saying so once on stderr: one
// deadline for the hub and then each body or device; 0 fails at once. Re-attached
// after a hub loss (hub_loss.hpp), it waits for them as long as it takes.
#pragma once

#include <cstdint>
#include <string>

#include "afhub/hub/bodies.hpp"

namespace afhub {

class StartupWait {
 public:
  // The deadline starts now (after survive_hub_loss(), when the process opts in).
  // Throws afhub::Error naming --wait unless `seconds` is 0 to 1e6.
  explicit StartupWait(double seconds);

  // connect_to_hub(role, HubPolicy::kRequire), waiting for the hub up to the seconds given.
  void connect_to_hub(const std::string& role) const;
  // wait_for_body() until the deadline; `hint` is added when it waited in vain.
  BodyEntry wait_for_body(const std::string& query, const std::string& who,
                          const std::string& hint = "wait longer with --wait") const;
  // The deadline (CLOCK_MONOTONIC ns; INT64_MAX after a re-attach), for other waits.
  std::int64_t give_up_ns() const { return give_up_ns_; }

 private:
  double seconds_;
  std::int64_t give_up_ns_;
};

}  // namespace afhub
