// afhub.Loop: a Python function run on the project's periodic loop runner (rt/), free
// or in lockstep with the physics, publishing its timing for `afhub top` as C++ loops
// do. The loop holds the GIL only while the function runs.
#include <pybind11/stl.h>
#include <unistd.h>

#include <algorithm>

#include <atomic>
#include <cstdio>
#include <exception>
#include <memory>
#include <optional>

#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/loop_stats_publisher.hpp"
#include "afhub/hub/physics_late_commands.hpp"
#include "afhub/hub/sample_waiter.hpp"
#include "afhub/hub/step_phase.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/rt/loop_timing.hpp"
#include "afhub/rt/periodic_loop.hpp"
#include "afhub/shm_layout/error.hpp"
#include "body.hpp"
#include "errors.hpp"

namespace afhub::python {
namespace {

class Loop {
 public:
  Loop(double rate_hz, py::function callback, std::optional<Body*> body, bool lockstep,
       std::string name, int fifo_priority, int cpu, bool lock_memory,
       std::optional<double> after_step_us, bool unaligned)
      : callback_(std::move(callback)),
        body_(body.value_or(nullptr)),
        lockstep_(lockstep),
        name_(std::move(name)) {
    if (lockstep && !body_)
      throw py::value_error("a lockstep loop answers a body's steps: give body=afhub.Body(...)");
    if (!lockstep && !(rate_hz >= kMinLoopRateHz && rate_hz <= kMaxLoopRateHz)) {
      char bounds[96];
      std::snprintf(bounds, sizeof bounds, "rate_hz takes a rate from %g to %g Hz", kMinLoopRateHz,
                    kMaxLoopRateHz);
      throw py::value_error(bounds);
    }
    if (fifo_priority < 0 || fifo_priority > 99)
      throw py::value_error("fifo_priority takes 0 (the normal scheduler) to 99");
    if (cpu < -1) throw py::value_error("cpu takes a CPU's number, or -1 for any CPU");
    require_no_nul(name_);
    options_.period_ns = lockstep ? 0 : static_cast<std::int64_t>(1e9 / rate_hz);
    if (after_step_us && unaligned)
      throw py::value_error("after_step_us and unaligned=True exclude each other");
    if (after_step_us && !(*after_step_us >= 0.0 && *after_step_us * 1e3 < options_.period_ns))
      throw py::value_error("after_step_us takes 0 up to the loop's period (" +
                            std::to_string(options_.period_ns / 1000) + " us)");
    // In phase with the physics by default, as `afhub ctl`'s controllers are.
    after_step_ns_ = unaligned       ? kAfterStepUnaligned
                     : after_step_us ? static_cast<std::int64_t>(*after_step_us * 1e3)
                                     : kAfterStepHalfPeriod;
    options_.fifo_priority = fifo_priority;
    options_.cpu = cpu;
    options_.lock_memory = lock_memory;
  }

  py::dict run(std::uint64_t cycles, double seconds) {
    // Checked and set under the GIL. Run again from its own callback it nested loops
    // until the stack overflowed (a segfault); from two threads, two ran at once.
    if (running_)
      throw std::runtime_error(
          "this Loop is running already (run() from its own callback, or from another "
          "thread): make another Loop, or return False from the callback to end this one");
    running_ = true;
    const struct Ran {
      bool& running;
      ~Ran() { running = false; }
    } ran{running_};
    ensure_connected();
    const std::int64_t end_ns = seconds != 0.0 ? deadline_after(seconds, "seconds") : 0;
    stop_ = false;
    error_ = nullptr;
    callbacks_ = 0;
    LoopTiming timing;
    LoopStats final_stats;
    const std::int64_t start_ns = monotonic_ns();
    if (body_) body_->set_lockstep(lockstep_);
    {
      py::gil_scoped_release release;
      const std::string who = "afhub python " + name_;
      const RealtimeGrant grant = apply_realtime(options_, who.c_str());
      LoopStatsPublisher stats(name_, body_ ? body_->channel() : "", options_.period_ns, lockstep_,
                               grant);
      if (lockstep_)
        run_lockstep(cycles, end_ns, timing, stats);
      else
        run_free(cycles, end_ns, timing, stats);
      timing.fill(final_stats);
      final_stats.rate_hz =
          static_cast<double>(timing.cycles()) * 1e9 /
          static_cast<double>(std::max<std::int64_t>(1, monotonic_ns() - start_ns));
    }
    if (body_) body_->set_lockstep(false);
    signals_.raise_if_pending();
    if (error_) std::rethrow_exception(error_);
    set_name(final_stats.name, name_);
    if (body_) set_name(final_stats.body, body_->channel());
    final_stats.period_s = static_cast<double>(options_.period_ns) * 1e-9;
    final_stats.lockstep = lockstep_;
    final_stats.header.publisher_pid = static_cast<std::uint32_t>(getpid());
    py::dict report = loop_stats_dict(final_stats);
    report["callbacks"] = callbacks_;
    return report;
  }

  void stop() { stop_ = true; }

 private:
  // Runs the callback under the GIL; false ends the loop (it returned False, stop()
  // was called, or it raised: the exception is raised again by run()).
  bool call(const BodyState* state) {
    ++callbacks_;
    py::gil_scoped_acquire acquire;
    try {
      const py::object result = state ? callback_(State(*state)) : callback_();
      if (result.is(py::bool_(false))) return false;
    } catch (...) {
      error_ = std::current_exception();
      return false;
    }
    return !stop_;
  }

  // False once the hub went away: the loop ends, and run() raises hub_gone().
  bool hub_still_here() {
    if (!hub_lost()) return true;
    error_ = std::make_exception_ptr(hub_gone());
    return false;
  }

  // The loop's clock: the real one, sleeping a long period in slices, so that Ctrl-C,
  // stop() and the end of run(seconds=) are seen within SignalWatch's 20 ms at any rate,
  // not a period (1000 s at 0.001 Hz) later. Short sleeps (1 kHz) take no GIL.
  class SlicedClock : public LoopClock {
   public:
    SlicedClock(Loop& loop, std::int64_t end_ns) : loop_(loop), end_ns_(end_ns) {}
    std::int64_t now_ns() noexcept override { return monotonic_ns(); }
    void sleep_until_ns(std::int64_t deadline_ns) noexcept override {
      for (std::int64_t now = monotonic_ns(); now < deadline_ns && !ended_; now = monotonic_ns()) {
        if (deadline_ns - now <= SignalWatch::kLookEveryNs) {
          afhub::sleep_until_ns(deadline_ns);
          return;
        }
        afhub::sleep_until_ns(now + SignalWatch::kLookEveryNs);
        ended_ = (end_ns_ && monotonic_ns() >= end_ns_) || loop_.stop_ || loop_.signals_pending();
      }
    }
    // The loop ends instead of running the cycle it slept for.
    bool ended() const noexcept { return ended_; }

   private:
    Loop& loop_;
    std::int64_t end_ns_;
    bool ended_ = false;
  };

  // Between cycles that run no Python: Ctrl-C still reaches the loop (raised by run()).
  bool signals_pending() noexcept { return signals_.pending(); }

  void run_free(std::uint64_t cycles, std::int64_t end_ns, LoopTiming& timing,
                LoopStatsPublisher& stats) {
    LoopOptions options = options_;
    options.max_cycles = cycles;
    SlicedClock clock(*this, end_ns);
    options.clock = &clock;
    PhysicsLateCommands late_commands;
    LoopCycle cycle;
    // With a body, woken after_step_ns after each of its steps is due (see StepPhase).
    std::optional<StepPhase> phase;
    const std::int64_t after_ns = after_step_offset_ns(after_step_ns_, options.period_ns);
    if (body_ && after_ns >= 0) {
      phase.emplace(
          after_ns, [this] { return body_->client().latest_state(); },
          &body_->client().state_reader());
      phase->attach(options, cycle);
    }
    const auto respond = [&](const BodyState& state) {
      timing.count_late(late_commands.newly_late(state));
      if (phase) phase->follow(state);
      return call(&state);
    };
    cycle.work = [&] {
      if (end_ns && monotonic_ns() >= end_ns) return false;
      if (!hub_still_here()) return false;
      if (!body_) return call(nullptr);
      const BodyState* state = body_->client().latest_state();
      if (!state) return !signals_pending();
      // A physics catching up after a stall: each of its late steps answered as it
      // comes (see controller.cpp), each a call of the function beyond the cycle's.
      while (state) {
        const StepPhase::Answered answered = StepPhase::Answered::of(*state);
        if (!respond(*state)) return false;
        state = phase ? phase->next_while_catching_up(answered) : nullptr;
      }
      return true;
    };
    cycle.after = [&](std::int64_t now) { stats.maybe_publish(now, timing); };
    cycle.wait = [&clock, in_phase = std::move(cycle.wait)] {
      return !clock.ended() && (!in_phase || in_phase());
    };
    run_periodic(options, timing, cycle);
  }

  // Each new step's state in, the callback's command out, as soon as the state
  // arrives; asleep on the state channel in between (see controller.cpp).
  void run_lockstep(std::uint64_t cycles, std::int64_t end_ns, LoopTiming& timing,
                    LoopStatsPublisher& stats) {
    SampleWaiter waiter;
    waiter.attach(body_->client().state_reader());
    bool answered_any = false;
    std::uint64_t last_step = 0;
    for (std::uint64_t done = 0; cycles == 0 || done < cycles;) {
      const BodyState* state = body_->client().latest_state();
      const std::int64_t now = monotonic_ns();
      if (end_ns && now >= end_ns) return;
      if (!hub_still_here()) return;
      stats.maybe_publish(now, timing);
      if (!state || (answered_any && state->header.sim_step == last_step)) {
        waiter.wait(10'000'000);
        if (stop_ || signals_pending()) return;
        continue;
      }
      const std::uint64_t step = state->header.sim_step;
      if (answered_any && step > last_step + 1) timing.count_late(step - last_step - 1);
      const bool go_on = call(state);
      timing.record(0, monotonic_ns() - now);
      answered_any = true;
      last_step = step;
      ++done;
      if (!go_on) return;
    }
  }

  py::function callback_;
  Body* body_;
  bool lockstep_;
  std::string name_;
  LoopOptions options_;
  std::int64_t after_step_ns_;     // an offset, kAfterStepHalfPeriod or kAfterStepUnaligned
  std::atomic<bool> stop_{false};  // stop() may come from another thread
  std::uint64_t callbacks_ = 0;    // calls of the function in this run()
  std::exception_ptr error_;
  SignalWatch signals_;
  bool running_ = false;
};

}  // namespace

void register_loop(py::module_& module) {
  py::class_<Loop>(
      module, "Loop",
      "A Python function run periodically on afhub's real-time loop runner, as C++ "
      "controllers run: absolute deadlines (no drift), periods a late cycle ran past "
      "skipped and counted, optional SCHED_FIFO, CPU pinning and locked memory. The loop "
      "holds the GIL only while the function runs, and publishes its timing once a second "
      "for `afhub top` (name, wake-up latency, compute time, overruns, late commands).\n\n"
      "Loop(rate_hz, callback, body=None, lockstep=False, name='python', fifo_priority=0, "
      "cpu=-1, lock_memory=False, after_step_us=None, unaligned=False)\n"
      "  without a body: callback() every period;\n"
      "  with body=afhub.Body(...): callback(state) every period with the body's newest "
      "state (afhub.State), once it has one, woken in phase with the physics: "
      "after_step_us after each step is due on the physics' clock (default: half the "
      "period), so that a command answers the newest state and arrives before the next "
      "step, as `afhub ctl --after-step` does; unaligned=True: on the loop's own clock;\n"
      "  lockstep=True (with a body; rate_hz is ignored): callback(state) once per physics "
      "step, as soon as the step's state arrives, and a physics run with `afhub run "
      "--lockstep` waits for the body's command: the callback must send one each time "
      "(body.command(...)), which then answers that step.\n"
      "The callback returning False, or calling loop.stop(), ends the loop; an exception "
      "it raises (Ctrl-C's KeyboardInterrupt too) ends it and is raised by run().")
      .def(py::init<double, py::function, std::optional<Body*>, bool, std::string, int, int, bool,
                    std::optional<double>, bool>(),
           py::arg("rate_hz"), py::arg("callback"), py::kw_only(), py::arg("body") = py::none(),
           py::arg("lockstep") = false, py::arg("name") = "python", py::arg("fifo_priority") = 0,
           py::arg("cpu") = -1, py::arg("lock_memory") = false,
           py::arg("after_step_us") = py::none(), py::arg("unaligned") = false,
           py::keep_alive<1, 4>())
      .def(
          "run", &Loop::run, py::arg("cycles") = 0, py::arg("seconds") = 0.0,
          "Runs until `cycles` cycles or `seconds` have passed (0: no limit), the callback "
          "ends it, or it raises. Returns the loop's statistics (as afhub.loop_stats() gives "
          "them) over the whole run, and 'callbacks': the function's calls, which can be more "
          "than the cycles: with a body, in phase, when the physics catches up after a stall (runs "
          "the steps it missed back to back), each of its late states is answered as it "
          "comes, within the cycle. SCHED_FIFO, CPU and memory locking, when asked for, "
          "apply to the calling thread and stay after run() returns.")
      .def("stop", &Loop::stop,
           "Ends the loop after the current cycle; from the callback or any other thread.");
}

}  // namespace afhub::python
