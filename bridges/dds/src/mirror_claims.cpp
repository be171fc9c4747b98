// Claims off the bridge's loop (see mirror_claims.hpp).
#include "mirror_claims.hpp"

#include <algorithm>
#include <cstdio>
#include <exception>
#include <utility>

#include "afhub/hub/hub_loss.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/shm_layout/error.hpp"

namespace afhub::bridges {

MirrorClaims::MirrorClaims(Limits limits)
    : limits_(limits),
      refused_(limits.max_refused, limits.retry_after_ns),
      thread_([this] { run(); }) {
  pending_.reserve(limits_.max_pending);
}

MirrorClaims::~MirrorClaims() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_one();
  thread_.join();
}

bool MirrorClaims::pending(std::string_view name) const noexcept {
  return std::find(pending_.begin(), pending_.end(), name) != pending_.end();
}

void MirrorClaims::forget_pending(std::string_view name) {
  const auto found = std::find(pending_.begin(), pending_.end(), name);
  if (found != pending_.end()) pending_.erase(found);
}

bool MirrorClaims::has_room() const {
  const std::lock_guard lock(mutex_);
  return pending_.size() < limits_.max_pending;
}

bool MirrorClaims::may_ask(std::string_view name) const {
  const std::lock_guard lock(mutex_);
  return !pending(name) && !refused_.recent(name, monotonic_ns());
}

bool MirrorClaims::ask(std::string_view name, Claim claim) {
  {
    const std::lock_guard lock(mutex_);
    if (pending_.size() >= limits_.max_pending || pending(name) ||
        refused_.recent(name, monotonic_ns()))
      return false;
    pending_.emplace_back(name);
    queue_.push_back({std::string(name), std::move(claim)});
  }
  wake_.notify_one();
  return true;
}

void MirrorClaims::install_claimed() {
  std::vector<Done> done;
  {
    const std::lock_guard lock(mutex_);
    if (done_.empty()) return;
    done.swap(done_);
  }
  for (Done& claimed : done) {
    try {
      claimed.install();
    } catch (const std::exception& error) {
      std::fprintf(stderr, "afhub bridge dds: not mirroring %s: %s\n", claimed.name.c_str(),
                   error.what());
    }
  }
  const std::lock_guard lock(mutex_);
  for (const Done& claimed : done) forget_pending(claimed.name);
}

bool MirrorClaims::drop_if_pending(std::string_view name) noexcept {
  const std::lock_guard lock(mutex_);
  if (!pending(name)) return false;
  ++states_dropped_;
  return true;
}

MirrorClaims::Counts MirrorClaims::counts() const {
  const std::lock_guard lock(mutex_);
  return {pending_.size(), refused_.size(), refusals_, states_dropped_};
}

void MirrorClaims::report() const {
  const Counts now = counts();
  std::fprintf(stderr,
               "afhub bridge dds: claims pending %zu, refused names %zu (%llu refusals, "
               "retried after %.0f s at the earliest), states dropped awaiting a claim %llu\n",
               now.pending, now.refused, static_cast<unsigned long long>(now.refusals),
               static_cast<double>(limits_.retry_after_ns) * 1e-9,
               static_cast<unsigned long long>(now.states_dropped));
}

// A claim that throws afhub::Error is a refusal, said the first time; anything else it
// throws (out of memory) is said, and the name may be asked for again. Once the hub is
// lost no claim runs: the process is about to re-attach (hub_loss.hpp).
void MirrorClaims::run() {
  std::unique_lock lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
    if (stopping_) return;
    Request request = std::move(queue_.front());
    queue_.pop_front();
    lock.unlock();
    Install install;
    std::string refusal, failure;
    if (!hub_lost()) {
      try {
        install = request.claim();
      } catch (const Error& error) {
        refusal = error.what();
      } catch (const std::exception& error) {
        failure = error.what();
      }
    }
    lock.lock();
    if (install) {
      done_.push_back({std::move(request.name), std::move(install)});
      continue;
    }
    forget_pending(request.name);
    const bool say = !refusal.empty() && refused_.add(request.name, monotonic_ns());
    if (!refusal.empty()) ++refusals_;
    lock.unlock();
    if (say)
      std::fprintf(stderr, "afhub bridge dds: not mirroring %s: %s\n", request.name.c_str(),
                   refusal.c_str());
    if (!failure.empty())
      std::fprintf(stderr, "afhub bridge dds: claiming %s failed: %s\n", request.name.c_str(),
                   failure.c_str());
    lock.lock();
  }
}

}  // namespace afhub::bridges
