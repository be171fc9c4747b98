// The simulation's channels: the lockstep barrier (answers, joins and drops),
// waiting for lockstep clients before the first step, and catch-up's wait for the
// controllers in phase.
#include <sched.h>

#include <algorithm>
#include <cstdio>

#include "afhub/hub/sample_waiter.hpp"
#include "afhub/physics/sim_channels.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"

namespace afhub::physics {
namespace {

std::string format_seconds(double seconds) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", seconds);
  return text;
}

}  // namespace

bool SimChannels::attach_command_waiter() {
  waiter_ = std::make_unique<SampleWaiter>();
  for (Channel& channel : channels_)
    if (!channel.soft && !waiter_->attach(channel.publisher->command_reader())) {
      waiter_.reset();
      return false;
    }
  return true;
}

void SimChannels::enable_lockstep(const LockstepOptions& options) {
  lockstep_ = true;
  lockstep_options_ = options;
  if (options.spin)
    waiter_.reset();
  else if (!waiter_)
    std::fprintf(stderr,
                 "afhub run: the lockstep wait can sleep on at most %zu bodies' commands; this "
                 "model has more, so it polls instead (as with --spin)\n",
                 SampleWaiter::kCapacity);
}

void SimChannels::wait_for_commands(std::int64_t until_ns) noexcept {
  if (waiter_)
    waiter_->wait(until_ns - monotonic_ns());
  else
    sched_yield();
}

void SimChannels::note_answer_pid(Channel& channel, std::uint32_t pid) noexcept {
  // Two live clients alternate (A, B, A); a client restarted after a kill answers alone
  // after the dead one (A, B, B), and gets a new pid.
  if (pid == channel.last_answer_pid) return;
  if (pid == channel.answer_pid_before)
    if (Notice* notice = note(channel, kShared, pid)) notice->other_pid = channel.last_answer_pid;
  channel.answer_pid_before = channel.last_answer_pid;
  channel.last_answer_pid = pid;
}

void SimChannels::note_lockstep_answer(Channel& channel, const Answer& answer) noexcept {
  note_answer_pid(channel, answer.pid);
  channel.answered_step = answer.step;
  if (answer.step != sim_.step_count()) return;  // an old step: no (re)join
  if (channel.lockstep_pid != answer.pid) {
    note(channel, kJoined, answer.pid)->step = answer.step;
    set_lockstep_pid(channel, answer.pid);
  }
  channel.misses = 0;
}

// Runs only when a body joins or leaves the barrier: the count is then read in O(1).
void SimChannels::set_lockstep_pid(Channel& channel, std::uint32_t pid) noexcept {
  auto find = [&](std::uint32_t wanted) {
    return std::find_if(lockstep_pids_.begin(), lockstep_pids_.end(),
                        [&](const auto& entry) { return entry.first == wanted; });
  };
  if (channel.lockstep_pid != 0) {
    const auto old = find(channel.lockstep_pid);
    if (old != lockstep_pids_.end() && --old->second == 0) {
      *old = lockstep_pids_.back();
      lockstep_pids_.pop_back();
    }
  }
  channel.lockstep_pid = pid;
  // Its answers are taken before another writer's newer command (`afhub cmd` beside it
  // hid them: each one hidden held the step for the client timeout).
  channel.publisher->command_reader().prefer_writer(pid);
  if (pid != 0) {
    const auto entry = find(pid);
    if (entry != lockstep_pids_.end())
      ++entry->second;
    else
      lockstep_pids_.emplace_back(pid, 1u);  // within the capacity reserved: no allocation
  }
  lockstep_client_count_ = static_cast<std::uint32_t>(lockstep_pids_.size());
}

bool SimChannels::hold_step_turn(std::int64_t now_ns, std::int64_t& republish_ns) noexcept {
  apply_commands(now_ns, true);
  if (stop_requested()) return false;
  // The held step again, freshly stamped: readers that judge a physics by its stamps
  // (`afhub status`, `world pause`, a controller's phase) see it alive while it waits.
  if (now_ns >= republish_ns) {
    publish(last_published_);
    republish_ns = now_ns + kRepublishWhileWaitingNs;
  }
  return true;
}

std::string SimChannels::bodies_without_client() const {
  constexpr int kListed = 8;
  std::string names;
  int count = 0;
  for (const Channel& channel : channels_) {
    if (channel.soft || channel.lockstep_pid != 0) continue;
    if (++count <= kListed) names += (names.empty() ? "" : ", ") + channel.publisher->channel();
  }
  if (count > kListed) names += " and " + std::to_string(count - kListed) + " more";
  return names;
}

bool SimChannels::wait_for_clients() {
  const std::uint32_t wanted = lockstep_options_.wait_for;
  if (lockstep_clients() >= wanted) return true;
  std::fprintf(stderr, "afhub run: waiting for %u lockstep clients before the first step\n",
               wanted);
  const std::int64_t start = monotonic_ns();
  std::int64_t republish_ns = start + kRepublishWhileWaitingNs;
  std::int64_t report_ns = start + lockstep_options_.wait_report_ns;
  while (lockstep_clients() < wanted) {
    const std::int64_t now = monotonic_ns();
    if (!hold_step_turn(now, republish_ns)) return false;
    report_events(stderr);  // setup, before the first step: joins are said as they come
    const double waited_s = static_cast<double>(now - start) * 1e-9;
    // The report first: even a process stalled past the timeout says it once.
    if (now >= report_ns) {
      std::fprintf(stderr,
                   "afhub run: still waiting after %.0f s: %u of %u lockstep clients joined; no "
                   "client yet for %s\n",
                   waited_s, lockstep_clients(), wanted, bodies_without_client().c_str());
      report_ns = now + lockstep_options_.wait_report_ns;
    }
    if (lockstep_options_.wait_timeout_ns > 0 && now - start >= lockstep_options_.wait_timeout_ns)
      throw Error("gave up after " + format_seconds(waited_s) + " s (--wait-timeout): " +
                  std::to_string(lockstep_clients()) + " of " + std::to_string(wanted) +
                  " lockstep clients joined; no client for " + bodies_without_client() +
                  ". Start them with `afhub ctl ... --lockstep`, or lower --wait-for");
    std::int64_t until = std::min(republish_ns, report_ns);
    if (lockstep_options_.wait_timeout_ns > 0)
      until = std::min(until, start + lockstep_options_.wait_timeout_ns);
    wait_for_commands(until);
  }
  return true;
}

bool SimChannels::await_lockstep() noexcept {
  const std::uint64_t step = sim_.step_count();
  const std::int64_t start = monotonic_ns();
  std::int64_t republish_ns = start + kRepublishWhileWaitingNs;
  for (;;) {
    const std::int64_t now = monotonic_ns();
    if (!hold_step_turn(now, republish_ns)) return false;
    bool pending = false;
    for (const Channel& channel : channels_)
      pending = pending || (channel.lockstep_pid != 0 && channel.answered_step != step);
    if (!pending) {
      for (Channel& channel : channels_) channel.misses = 0;
      return true;
    }
    if (now - start > lockstep_options_.client_timeout_ns) break;
    wait_for_commands(std::min(republish_ns, start + lockstep_options_.client_timeout_ns + 1));
  }
  // Timed out: the step goes ahead without the late answers.
  for (Channel& channel : channels_) {
    if (channel.lockstep_pid == 0 || channel.answered_step == step) continue;
    ++late_answers_;
    if (++channel.misses < lockstep_options_.max_misses) continue;
    note(channel, kDropped, channel.lockstep_pid)->misses = channel.misses;
    set_lockstep_pid(channel, 0);
    channel.misses = 0;
    ++dropped_;
  }
  return true;
}

void SimChannels::await_answers_in_phase(std::int64_t timeout_ns) noexcept {
  const std::uint64_t step = sim_.step_count();
  const std::int64_t until_ns = monotonic_ns() + timeout_ns;
  const auto pending = [step](const Channel& channel) {
    return channel.in_phase && channel.commanded && channel.applied_answer_step != step;
  };
  for (;;) {
    const std::int64_t now = monotonic_ns();
    apply_commands(now);
    if (std::none_of(channels_.begin(), channels_.end(), pending) || stop_requested()) return;
    if (now >= until_ns) break;
    wait_for_commands(until_ns);
  }
  for (Channel& channel : channels_)
    if (pending(channel) && ++channel.phase_misses >= kPhaseMisses) {
      channel.in_phase = false;
      channel.phase_misses = 0;
    }
}

}  // namespace afhub::physics
