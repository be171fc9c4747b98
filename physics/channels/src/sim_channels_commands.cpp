// The simulation's channels: applying bodies' commands, the command watchdog, the
// notices of refused, stale and expired commands and their text, forgetting commands.
#include <algorithm>
#include <cstdio>

#include "afhub/physics/sim_channels.hpp"
#include "afhub/shm_layout/error.hpp"
#include "command_input.hpp"

namespace afhub::physics {

void SimChannels::apply_commands(std::int64_t now_ns, bool holding) noexcept {
  for (std::size_t c = 0; c < channels_.size(); ++c) {
    Channel& channel = channels_[c];
    // The command slots were last written by a controller on another core: asked for
    // a few bodies ahead, their lines come while this one is read.
    if (c + kBodyPrefetchAhead < channels_.size())
      channels_[c + kBodyPrefetchAhead].publisher->prefetch_command();
    if (channel.soft) continue;  // soft bodies take no commands
    const BodyCommand* command = channel.publisher->latest_command();
    const bool updated = command && channel.publisher->command_updated();
    if (updated && command->lockstep == BodyCommand::kLockstepKeep) {
      // An answer alone: the command in force, and its watchdog, go on.
      if (lockstep_)
        note_lockstep_answer(channel,
                             {command->header.sim_step, command->header.publisher_pid, true});
      if (channel.commanded) channel.last_command_ns = now_ns;
    } else if (updated) {
      // Copied out of shared memory once, then checked, then applied.
      channel.taken_command = command;
      to_input(*command, input_);
      const Answer answer{command->header.sim_step, command->header.publisher_pid,
                          command->lockstep != 0};
      // Its age by its publish stamp (the same monotonic clock in every process),
      // not by when this process first saw it. A stamp from the future (a forged or
      // broken writer) is no fresher than an old one: past a small allowance it is
      // ignored too, or it would hold the watchdog off for as long as it is ahead.
      const std::int64_t stamp_ns = command->header.publish_stamp_ns;
      std::int64_t age_ns = now_ns - stamp_ns;
      if (age_ns < -kFutureStampAllowanceNs) {
        // Or published after `now_ns` was read, this thread preempted meanwhile (for
        // milliseconds on a loaded machine): judged again by the clock as it is now.
        now_ns = monotonic_ns();
        age_ns = now_ns - stamp_ns;
      }
      // A lockstep answer to the step the barrier holds, written after that step went
      // out, is as fresh as the step, however long the physics was stopped before it read
      // it (it was ignored as old, and the step went on without it). One older answers
      // another run's step of that number (a physics restarted, or reset).
      const bool answers_held_step = lockstep_ && answer.lockstep &&
                                     answer.step == sim_.step_count() &&
                                     stamp_ns >= step_published_ns_;
      if ((age_ns > channel.watchdog_ns && !answers_held_step) ||
          age_ns < -kFutureStampAllowanceNs) {
        ++stale_;
        if (Notice* notice = note(channel, kStale, answer.pid))
          notice->seconds = static_cast<double>(age_ns) * 1e-9;
      } else if (answer.step > sim_.step_count()) {
        // It answers a state this run has not published: one from before a world reset
        // or a restart of the physics. Applied, a free-running controller's last target
        // for the old pose kicked the KUKA's joints at 19 to 34 rad/s in the first steps.
        ++stale_;
        if (Notice* notice = note(channel, kAhead, answer.pid)) notice->step = answer.step;
      } else if (const char* problem = sim_.input_problem(channel.index, input_)) {
        ++rejected_;
        ++channel.refused;
        channel.refused_pid = answer.pid;
        set_name(channel.refusal_reason, problem);
        if (Notice* notice = note(channel, kRejected, answer.pid)) set_name(notice->why, problem);
      } else {
        // Entries for joints without an axis are refused and counted; the rest applies.
        if (const char* entry = sim_.axisless_entry(channel.index, input_)) {
          ++rejected_;
          if (Notice* notice = note(channel, kAxisless, answer.pid)) set_name(notice->why, entry);
        }
        // Said once per sender (a controller sends its mistake every step), for the last
        // few senders: a second controller's mistake went unsaid once the first's was.
        auto& told = channel.told_beyond_limits;
        if (!channel.notices[kBeyondLimits].pending &&
            std::find(told.begin(), told.end(), answer.pid) == told.end())
          if (const char* entry = sim_.beyond_limits_entry(channel.index, input_)) {
            told[channel.told_beyond_limits_count++ % told.size()] = answer.pid;
            channel.notices[kBeyondLimits].said = false;
            if (Notice* notice = note(channel, kBeyondLimits, answer.pid))
              set_name(notice->why, entry);
          }
        if (lockstep_ && answer.lockstep) {
          note_lockstep_answer(channel, answer);
        } else if (lockstep_ && channel.lockstep_pid != 0 && answer.pid != channel.lockstep_pid) {
          // Each step takes whichever command came last (the client's answers are taken
          // first, so none is hidden).
          if (Notice* notice = note(channel, kBesideLockstep, answer.pid))
            notice->other_pid = channel.lockstep_pid;
        }
        channel.applied_answer_step = answer.step;
        sim_.set_input(channel.index, input_);
        channel.last_command_ns = std::min(stamp_ns, now_ns);
        channel.commanded = true;
      }
    }
    // A lockstep client's command does not age while the barrier holds a step, for it or
    // for the others, nor on the step it answered, taken when the hold ends: the
    // simulation waits. Its silence is the barrier's to judge (--client-timeout); once it
    // has missed a step, or steps go on without it (`world step` while paused), the
    // watchdog's too. (Its command to step 0 expired when the last client came 0.5 s
    // later, and a client stalled on a loaded machine lost its command while the physics
    // held the step for it.)
    const bool held_for = lockstep_ && channel.lockstep_pid != 0 && channel.misses == 0 &&
                          (holding || channel.answered_step == sim_.step_count());
    if (channel.commanded && !held_for && now_ns - channel.last_command_ns > channel.watchdog_ns) {
      if (channel.hold_on_watchdog)
        sim_.hold_joints(channel.index);
      else
        sim_.clear_input(channel.index);
      channel.commanded = false;
      ++expiries_;
      note(channel, kExpired, 0);
    }
  }
}

SimChannels::Notice* SimChannels::note(Channel& channel, Event event, std::uint32_t pid) noexcept {
  Notice& notice = channel.notices[event];
  // Said once: the first occurrence's details stay until reported, later ones are counts.
  if (said_once(event) && (notice.said || notice.pending)) return nullptr;
  notice.pending = true;
  notice.pid = pid;
  return &notice;
}

int SimChannels::report_events(std::FILE* out) {
  int lines = 0;
  for (Channel& channel : channels_) {
    const char* body = channel.publisher->channel().c_str();
    for (int event = 0; event < kEventKinds; ++event) {
      Notice& n = channel.notices[event];
      if (!n.pending) continue;
      n.pending = false;
      n.said = said_once(static_cast<Event>(event));
      ++lines;
      switch (event) {
        case kStale:
          if (n.seconds < 0.0)
            std::fprintf(out,
                         "afhub run: ignored a command for %s from pid %u: stamped %.3f s in the "
                         "future (a forged stamp, or a writer on another clock; counted in "
                         "`afhub status`)\n",
                         body, n.pid, -n.seconds);
          else
            std::fprintf(out,
                         "afhub run: ignored a command for %s from pid %u: published %.3f s ago, "
                         "older than the body's watchdog of %.3f s (counted in `afhub status`)\n",
                         body, n.pid, n.seconds, static_cast<double>(channel.watchdog_ns) * 1e-9);
          break;
        case kAhead:
          std::fprintf(out,
                       "afhub run: ignored commands for %s from pid %u answering step %llu, which "
                       "this run has not reached: sent before a world reset or a restart of the "
                       "physics (its next command, answering a new state, is taken; counted in "
                       "`afhub status`; said once per body)\n",
                       body, n.pid, static_cast<unsigned long long>(n.step));
          break;
        case kRejected:
          std::fprintf(out,
                       "afhub run: refused a command for %s: %s (from pid %u; counted in `afhub "
                       "status`; said once per body)\n",
                       body, n.why.data(), n.pid);
          break;
        case kAxisless:
          std::fprintf(out,
                       "afhub run: refused part of a command for %s: %s (from pid %u; counted "
                       "in `afhub status`; said once per body)\n",
                       body, n.why.data(), n.pid);
          break;
        case kBeyondLimits:
          std::fprintf(out,
                       "afhub run: a command for %s holds a target it cannot reach: %s (from pid "
                       "%u; said once per sender)\n",
                       body, n.why.data(), n.pid);
          break;
        case kExpired:
          std::fprintf(out,
                       "afhub run: no command for %s in %.3f s: %s until commands come again "
                       "(said once; `afhub status` counts every expiry)\n",
                       body, static_cast<double>(channel.watchdog_ns) * 1e-9,
                       channel.hold_on_watchdog ? "its joints hold their positions"
                                                : "its wrench and the efforts it drove are zero");
          break;
        case kShared:
          std::fprintf(out,
                       "afhub run: two lockstep clients command %s, pids %u and %u: each step "
                       "takes whichever command came last, so the run depends on their timing "
                       "(said once per body); run one lockstep client per body\n",
                       body, n.other_pid, n.pid);
          break;
        case kBesideLockstep:
          std::fprintf(out,
                       "afhub run: pid %u commands %s outside the lockstep, beside its lockstep "
                       "client pid %u: each step takes whichever command came last, so the run "
                       "depends on their timing (said once per body); command a lockstep body "
                       "from its lockstep client only\n",
                       n.pid, body, n.other_pid);
          break;
        case kJoined:
          std::fprintf(out,
                       "afhub run: lockstep client pid %u joined the barrier for %s at step %llu\n",
                       n.pid, body, static_cast<unsigned long long>(n.step));
          break;
        case kDropped:
          std::fprintf(out,
                       "afhub run: lockstep client pid %u missed %d steps in a row for %s; dropped "
                       "from the barrier (it rejoins by answering a current step)\n",
                       n.pid, n.misses, body);
          break;
        default:
          break;
      }
    }
  }
  return lines;
}

void SimChannels::forget_commands() noexcept {
  for (Channel& channel : channels_) {
    channel.commanded = false;
    channel.answered_step = 0;
    channel.applied_answer_step = 0;
    channel.state_command_step = -1;
    channel.in_phase = false;
    channel.phase_misses = 0;
    channel.misses = 0;
  }
  timeliness_step_ = 0;
}

SimChannels::Channel& SimChannels::active_channel(const std::string& body, const char* option) {
  std::vector<std::string> active;
  for (const Channel& channel : channels_)
    if (!channel.soft) active.push_back(channel.publisher->channel());
  std::string name;
  try {
    name = resolve_body(body, active);
  } catch (const Error& error) {
    throw Error(std::string(option) + ": " + error.what());
  }
  for (Channel& channel : channels_)
    if (!channel.soft && channel.publisher->channel() == name) return channel;
  throw Error(std::string(option) + ": no active body " + name);
}

void SimChannels::hold_on_watchdog(const std::string& body) {
  active_channel(body, "--watchdog-hold").hold_on_watchdog = true;
}

void SimChannels::set_watchdog(const std::string& body, double seconds) {
  if (!(seconds >= kMinWatchdogS && seconds <= kMaxWatchdogS))
    throw Error("--watchdog-body: the watchdog of '" + body + "' must be 0.002 to 3600 s, got " +
                std::to_string(seconds));
  active_channel(body, "--watchdog-body").watchdog_ns = static_cast<std::int64_t>(seconds * 1e9);
}

}  // namespace afhub::physics
