// Watching the hub while iceoryx registers this process (connect_to_hub): iceoryx's
// registration does not see its hub die before answering. Measured with a hub
// SIGKILLed a few milliseconds after `afhub ls` started: the client retried for 60 s,
// then aborted on an assertion, or sent to the dead socket for over 90 s.
#pragma once

#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

namespace afhub {

// While it lives, a thread looks at the hub every 20 ms. Seen up and then gone (its
// socket refuses, or another hub replaced it: two looks in a row), the registration
// cannot end: a process that outlives its hub (survive_hub_loss) re-executes to wait
// for the next one, any other says so as `who` and exits with code 1 (it has done
// nothing yet).
class RegistrationGuard {
 public:
  explicit RegistrationGuard(std::string who);
  ~RegistrationGuard();
  RegistrationGuard(const RegistrationGuard&) = delete;
  RegistrationGuard& operator=(const RegistrationGuard&) = delete;

 private:
  void watch() noexcept;
  [[noreturn]] void end_registration() noexcept;

  const std::string who_;
  std::mutex mutex_;
  std::condition_variable registered_;
  bool seen_ = false;  // the hub, up when the registration began
  bool done_ = false;
  std::thread thread_;
};

}  // namespace afhub
