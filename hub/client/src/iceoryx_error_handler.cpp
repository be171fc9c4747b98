// The iceoryx error handler of a process that outlives its hub (see
// iceoryx_error_handler.hpp).
#include "iceoryx_error_handler.hpp"

#include <unistd.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <functional>

#include "afhub/shm_layout/header.hpp"
#include "hub_loss_handling.hpp"
#include "hub_loss_state.hpp"
#include "iceoryx_hoofs/error_handling/error_handling.hpp"

namespace afhub::hub_loss {
namespace {

// A fatal iceoryx error is a lost hub only when the hub goes within this long.
constexpr std::int64_t kFatalErrorGraceNs = 3'000'000'000;

// Whether `error` is met for the first time in this process; kinds past the table's
// room count as said.
bool first_time(iox::Error error) noexcept {
  static std::array<std::atomic<std::uint32_t>, 64> said{};  // error codes + 1; 0 is free
  const auto code = static_cast<std::uint32_t>(error) + 1;
  for (auto& slot : said) {
    std::uint32_t seen = 0;
    if (slot.compare_exchange_strong(seen, code)) return true;  // a free slot, now this kind's
    if (seen == code) return false;
  }
  return false;
}

void on_iceoryx_error(const iox::Error error, const std::function<void()> callback,
                      const iox::ErrorLevel level) {
  const char* name = iox::ErrorHandler::toString(error);
  const std::string& who = state().who;
  if (level != iox::ErrorLevel::FATAL) {
    // Said once per kind: a loop meeting it each step would write megabytes a minute.
    // A pool out of chunks is said with the pool (iceoryx_stderr_filter.hpp).
    if (error != iox::Error::kMEPOO__MEMPOOL_GETCHUNK_POOL_IS_RUNNING_OUT_OF_CHUNKS &&
        first_time(error))
      std::fprintf(stderr, "%s: iceoryx: %s (said once)\n", who.c_str(), name);
    if (callback) callback();
    return;
  }
  // iceoryx's call cannot go on past a fatal error, nor can a process that does not
  // re-execute re-attach: it ends here, saying why.
  const auto end_without_hub = [&] {
    std::fprintf(stderr, "%s: iceoryx: %s after the hub went away: ending this process\n",
                 who.c_str(), name);
    _exit(1);
  };
  if (state().handling) {
    if (!state().reexecs) end_without_hub();
    wait_for_reexec();
  }
  for (const std::int64_t give_up = monotonic_ns() + kFatalErrorGraceNs; monotonic_ns() < give_up;
       sleep_ns(kReattachPollNs)) {
    if (!hub_gone()) continue;
    char why[160];
    std::snprintf(why, sizeof why, "iceoryx: %s", name);
    if (handle_loss(why) == LossHandling::kStopping) _exit(0);
    if (!state().reexecs) end_without_hub();
    wait_for_reexec();
  }
  std::fprintf(stderr, "%s: fatal iceoryx error %s, with the hub still up\n", who.c_str(), name);
  if (callback) callback();
  std::abort();
}

}  // namespace

void install_iceoryx_error_handler() {
  static iox::cxx::GenericRAII handler = iox::ErrorHandler::setTemporaryErrorHandler(
      [](const iox::Error error, const std::function<void()> callback,
         const iox::ErrorLevel level) { on_iceoryx_error(error, callback, level); });
}

}  // namespace afhub::hub_loss
