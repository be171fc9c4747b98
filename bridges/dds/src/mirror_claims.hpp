// Claiming mirrored bodies and devices off the bridge's loop. A claim asks the hub for
// room (hub/body_claims.hpp: its catalog and free ports, up to 2.5 s) and opens
// iceoryx ports; on the loop it stalled all the loop carries (the commands written to
// mirrored bodies, devices, the world, the status), and the far side dropped the late
// commands as stale. Here claims run one at a time, in the order asked, on a thread of
// their own; each hands back what is left for the loop's thread (putting what it made
// in place), which the loop runs in install_claimed(). The loop only queues, and never
// waits: at most max_pending names are queued or under way, and past that ask()
// declines (a body's announcement waits in its DDS reader, a device asks again with
// its next state). States of a name being claimed are dropped, counted, until it is
// in place. A refused name is said once and not claimed again for retry_after
// (refused_names.hpp). The status line says all of this.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "refused_names.hpp"

namespace afhub::bridges {

class MirrorClaims {
 public:
  // Run on the loop's thread once its claim is done: puts what the claim made in place.
  using Install = std::function<void()>;
  // Run on the claims' thread: returns its Install, or throws afhub::Error saying why
  // the name is refused.
  using Claim = std::function<Install()>;

  struct Limits {
    std::size_t max_pending = 64;
    std::size_t max_refused = 1024;
    std::int64_t retry_after_ns = 10'000'000'000;
  };
  struct Counts {
    std::size_t pending = 0, refused = 0;
    std::uint64_t refusals = 0, states_dropped = 0;
  };

  explicit MirrorClaims(Limits limits);
  ~MirrorClaims();  // waits for the claim under way; the queued ones are dropped
  MirrorClaims(const MirrorClaims&) = delete;
  MirrorClaims& operator=(const MirrorClaims&) = delete;

  // On the loop's thread. Whether a claim can be queued now.
  bool has_room() const;
  // Whether `name` may be asked for: not being claimed, not refused lately. Allocates
  // nothing.
  bool may_ask(std::string_view name) const;
  // Queues `claim` for `name`; false (and nothing queued) when there is no room or
  // `name` may not be asked for.
  bool ask(std::string_view name, Claim claim);
  // Runs the Installs of the claims done since the last call.
  void install_claimed();

  // On any thread, for a state of `name` that has nowhere to go: whether `name` is
  // being claimed (the state is then counted as dropped). Allocates nothing.
  bool drop_if_pending(std::string_view name) noexcept;
  Counts counts() const;
  void report() const;

 private:
  struct Request {
    std::string name;
    Claim claim;
  };
  struct Done {
    std::string name;
    Install install;
  };

  void run();
  bool pending(std::string_view name) const noexcept;  // with mutex_ held
  void forget_pending(std::string_view name);          // with mutex_ held

  const Limits limits_;
  mutable std::mutex mutex_;  // never held during a claim or an install
  std::condition_variable wake_;
  std::deque<Request> queue_;
  std::vector<std::string> pending_;  // queued, under way, or done and not in place yet
  std::vector<Done> done_;
  RefusedNames refused_;
  std::uint64_t refusals_ = 0, states_dropped_ = 0;
  bool stopping_ = false;
  std::thread thread_;  // last: starts once the rest is made
};

}  // namespace afhub::bridges
