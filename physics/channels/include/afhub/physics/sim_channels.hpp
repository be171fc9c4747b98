// The simulation on the hub's channels: each active body (not `passive`) and each
// soft body publishes its state and reads its command slot; the world publishes
// its clock, counters, lights and cameras, and reads world commands.
// This adapter is the one place where the wire payloads (BodyCommand, BodyState,
// WorldState) meet the core's types (BodyInput, BodyReading): a command is copied
// out of shared memory once, checked (against the body's physical bounds too: see
// InputBounds), then applied. A command older than its body's watchdog period when
// read, by its publish stamp, is stale and not applied (a restarted physics never
// applies a live controller's old command as new). A per-body watchdog (0.5 s by
// default, down to 2 ms for haptics) zeroes or holds what that body commanded when
// its commands stop coming. World commands are read as a queue, every command from
// every writer once, in order, keyed by (publisher pid, sequence).
// Needs connect_to_hub() first.
//
// Catch-up (await_answers_in_phase): a step run late, back to back with the one
// before, waits a moment for the answers of the controllers in phase.
//
// Lockstep (enable_lockstep): a body whose command is marked lockstep and answers
// the current step joins the barrier; await_lockstep() then holds the step until
// every body in the barrier has an answer for it. A body whose answer is later than
// the client timeout is counted late; after `max_misses` late steps in a row it
// leaves the barrier (a dead client never freezes the world), and it rejoins with
// its next answer to a current step. A held step is published again every 20 ms:
// state channels keep no history, and a client joining during the wait needs it.
//
// Nothing in the loop writes to stderr or allocates: what happened (a command
// refused or stale, a watchdog expiry, a lockstep client joining or dropped) is
// counted, kept in fixed storage, and said by report_events(), which the caller runs
// outside the loop's timed part (run_loop: at most once a second, and at the end).
//
// Written in sim_channels.cpp (set-up, states, the world), sim_channels_commands.cpp
// (commands, the watchdog, events), sim_channels_lockstep.cpp and sim_channels_view.cpp
// (the scene and the viewers' feeds).
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string_view>
#include <utility>
#include <vector>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/step_tape.hpp"
#include "afhub/physics/simulation.hpp"
#include "afhub/shm_layout/body_command.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/scene.hpp"
#include "afhub/shm_layout/scene_poses.hpp"
#include "afhub/shm_layout/soft_body.hpp"
#include "afhub/shm_layout/world.hpp"
#include "afhub/shm_layout/world_control.hpp"

namespace afhub {
class SampleWaiter;
class WorldCommandQueue;
}  // namespace afhub

namespace afhub::physics {

struct LockstepOptions {
  std::uint32_t wait_for = 0;                    // hold step 0 until this many clients joined
  std::int64_t wait_timeout_ns = 0;              // give up waiting for them after this; 0: never
  std::int64_t wait_report_ns = 2'000'000'000;   // say whom it still waits for this often
  std::int64_t client_timeout_ns = 100'000'000;  // how long a step waits for an answer
  int max_misses = 3;                            // late steps in a row before a client is dropped
  // How the waits for answers wait: false, asleep on the command channels (a futex,
  // iceoryx's WaitSet) until a command comes; true, polling with sched_yield, for a
  // process given a core of its own (under SCHED_FIFO a yield never lets a client run).
  bool spin = false;
};

class SimChannels {
 public:
  // `watchdog_s`: every body's watchdog period, until set_watchdog changes one.
  // `name_space`: the world's channels go under it too (world_instance), as the
  // bodies' do (prefix_channels): a second copy of a model has a world of its own.
  SimChannels(Simulation& sim, double watchdog_s, std::string_view name_space = {});
  ~SimChannels();

  // Body `body`'s watchdog period (a name as for hold_on_watchdog): its commands
  // older than this are stale, and this long without one its commands are released.
  // Throws afhub::Error for an unknown body or a period outside [0.002, 3600] s.
  void set_watchdog(const std::string& body, double seconds);
  // The smallest and largest watchdog period accepted, in seconds.
  static constexpr double kMinWatchdogS = 0.002, kMaxWatchdogS = 3600.0;

  // The watchdog's policy for a body (its channel name or a suffix after a '/'):
  // hold its joints where they are instead of zeroing efforts. Throws afhub::Error
  // listing the candidates when no active body matches or the name is ambiguous.
  void hold_on_watchdog(const std::string& body);

  void enable_lockstep(const LockstepOptions& options);
  bool lockstep() const { return lockstep_; }
  // Before the first step: holds step 0 (publishing it again, applying commands)
  // until `wait_for` lockstep clients joined, saying every `wait_report_ns` how many
  // joined and which bodies have no client yet. False when a stop signal came;
  // throws afhub::Error when `wait_timeout_ns` passes first.
  bool wait_for_clients();
  // Applies commands as they come until every body in the barrier has answered the
  // current step, or the timeout. False when a stop signal came while waiting.
  bool await_lockstep() noexcept;
  // Before a step of a free-running world behind its grid (after a stall it runs its
  // late steps back to back): applies commands as they come until each body whose
  // controller is in phase (its commands were in time, and it has not missed this wait
  // kPhaseMisses times in a row since) has an answer to the current step, or for
  // `timeout_ns`. A controller that follows a catching-up physics (hub/step_phase.hpp)
  // so stays in time, also when it wakes from the same stall a little after the
  // physics; one that does not costs this wait kPhaseMisses times.
  void await_answers_in_phase(std::int64_t timeout_ns) noexcept;
  // A controller woken by the same stall as the physics may take a few hand-offs to
  // answer (measured in docs/performance.md, "The 1 kHz loop").
  static constexpr int kPhaseMisses = 3;

  // After a world reset (the simulation's inputs cleared, its steps from 0): no body
  // is under command, and no lockstep answer or timeliness count carries across.
  void forget_commands() noexcept;
  // Reads each body's newest command, applies it, and runs the watchdogs. `holding`: the
  // lockstep barrier holds the step (a lockstep client's command does not age then).
  void apply_commands(std::int64_t now_ns, bool holding = false) noexcept;
  // The world's clock as published with the states.
  struct WorldClock {
    double wall_time_s = 0.0;
    double achieved_rate_hz = 0.0;
    WorldControl control;  // paused or not, and by whom
    // The step's deadline on the loop's grid, and its period (0, 0: not paced).
    std::int64_t step_due_ns = 0, step_period_ns = 0;
  };
  // Publishes every body's state and the world state.
  void publish(const WorldClock& clock) noexcept;
  // The world's controls as they are now, for the step republished while it waits for
  // lockstep answers (a resume acted on before the wait showed paused until it ended).
  void update_world_control(const WorldControl& control) noexcept {
    last_published_.control = control;
  }
  // What a viewer reads, at most kViewerRateHz of `now_ns` (CLOCK_MONOTONIC), paused
  // too, each only while something reads it (once without, for a viewer that joins
  // later): every scene body's pose and joints in one payload (ScenePoses), and each
  // soft body's node positions. Called outside the loop's timed step (run_loop: the
  // cycle's `after`, with the loop statistics): the states are out by then, and no
  // controller waits for it.
  void publish_view(std::int64_t now_ns) noexcept;
  // Between steps, outside the timed step: readies the step tape's next part
  // (StepTapeWriter::prepare) while a recorder reads the tape.
  void prepare_next_step() noexcept { tape_.prepare(); }
  // The next world command not acted on before, oldest first, copied into `out`;
  // false when none waits. Commands published before this SimChannels existed (a
  // live writer's history seen by a restarted physics) are skipped.
  bool next_world_command(WorldCommand& out) noexcept;

  std::size_t channel_count() const { return channels_.size(); }
  std::uint64_t rejected_commands() const { return rejected_; }
  std::uint64_t watchdog_expiries() const { return expiries_; }
  std::uint64_t stale_commands() const { return stale_; }
  // The distinct lockstep clients in the barrier, kept as they join and leave.
  std::uint32_t lockstep_clients() const noexcept { return lockstep_client_count_; }

  std::uint64_t late_answers() const { return late_answers_; }
  std::uint64_t dropped_clients() const { return dropped_; }
  std::uint64_t commanded_steps() const { return commanded_steps_; }
  std::uint64_t answered_steps() const { return answered_steps_; }

  // Writes the events noted since the last call (see above) to `out`, one line each,
  // and returns how many it wrote. Not real-time: call it outside the loop's timed part.
  int report_events(std::FILE* out);

 private:
  // Publishes the scene description once, keeping it for viewers that join later.
  void publish_scene();
  // Publishes each soft body's faces once, keeping them for viewers that join later.
  void publish_soft_faces();
  // publish_view's two parts.
  void publish_scene_poses() noexcept;
  void publish_soft_nodes() noexcept;
  // An event to say from outside the loop. Refusals, stale commands, expiries and a
  // second lockstep client are said once per body (a short watchdog may fire every few
  // ms, two clients alternate every step), and so is a writer beside a lockstep client;
  // joins and drops each time.
  // How far ahead of this process's clock a command's stamp may be: every process
  // reads the same CLOCK_MONOTONIC, so only a read racing the publish on another core.
  static constexpr std::int64_t kFutureStampAllowanceNs = 1'000'000;
  enum Event {
    kStale,
    kAhead,
    kRejected,
    kAxisless,
    kBeyondLimits,
    kExpired,
    kShared,
    kBesideLockstep,
    kJoined,
    kDropped,
    kEventKinds
  };
  struct Notice {
    bool pending = false;  // noted since the last report
    bool said = false;
    std::uint32_t pid = 0;
    double seconds = 0.0;         // kStale: the command's age (< 0: from the future)
    std::uint32_t other_pid = 0;  // kShared, kBesideLockstep: the client in the barrier
    std::uint64_t step = 0;       // kJoined: the step it joined at; kAhead: it answered
    int misses = 0;               // kDropped: late steps in a row
    std::array<char, 160> why{};  // kRejected, kAxisless, kBeyondLimits: the problem
  };
  struct Channel {
    std::size_t index = 0;  // into model bodies, or soft bodies when `soft`
    bool soft = false;
    std::unique_ptr<BodyPublisher> publisher;
    std::uint32_t joint_count = 0;
    std::uint32_t actuator_count = 0;
    std::uint32_t ray_count = 0;  // its sensors' rays
    std::int64_t watchdog_ns = 0;
    std::int64_t last_command_ns = 0;  // the publish stamp of the command being applied
    bool commanded = false;            // a command is being applied (the watchdog is armed)
    bool hold_on_watchdog = false;     // the watchdog holds the joints rather than zeroing efforts
    // What report_events() says about this body; noted in the loop without allocating.
    std::array<Notice, kEventKinds> notices{};
    // The senders last told of a target beyond a joint's limits (kBeyondLimits).
    std::array<std::uint32_t, 4> told_beyond_limits{};
    std::uint32_t told_beyond_limits_count = 0;
    std::uint64_t commanded_steps = 0, answered_steps = 0;  // this body's timeliness
    // The commands refused for this body, and the last one's sender and reason, as its
    // state publishes them (BodyState::refused_commands).
    std::uint32_t refused = 0, refused_pid = 0;
    std::array<char, kRefusalReasonSize> refusal_reason{};
    std::uint32_t lockstep_pid = 0;         // the lockstep client answering for this body; 0: none
    std::uint64_t answered_step = 0;        // lockstep: the step this client answered last
    std::uint64_t applied_answer_step = 0;  // the step the command being applied answers
    // BodyState::command_answered_step of the last step taken (-1: no command in force).
    std::int64_t state_command_step = -1;
    bool in_phase = false;  // a command in time since kPhaseMisses missed hand-offs in a row
    int phase_misses = 0;   // await_answers_in_phase's timeouts in a row
    int misses = 0;         // late lockstep steps in a row
    // The last two clients that answered for this body, the last one first.
    std::uint32_t last_answer_pid = 0, answer_pid_before = 0;
    // The command taken since the last publish (the reader's checked copy), for the tape.
    const BodyCommand* taken_command = nullptr;
    void prefetch_state_update() const noexcept { publisher->prefetch_state_update(ray_count); }
  };
  // The notice to fill for `event`, or nullptr when a said-once event was noted already.
  static Notice* note(Channel& channel, Event event, std::uint32_t pid) noexcept;
  static bool said_once(Event event) { return event <= kBesideLockstep; }
  // Puts `channel` in the barrier for client `pid` (0: out of it), keeping the count.
  void set_lockstep_pid(Channel& channel, std::uint32_t pid) noexcept;
  // The world's clock as last published, for publishing a held step again.
  static constexpr std::int64_t kRepublishWhileWaitingNs = 20'000'000;

  // What a command's header says about the step it answers, copied with the command.
  struct Answer {
    std::uint64_t step = 0;
    std::uint32_t pid = 0;
    bool lockstep = false;
  };
  // Notes which client answered: two that alternate on one body are said.
  void note_answer_pid(Channel& channel, std::uint32_t pid) noexcept;
  void note_lockstep_answer(Channel& channel, const Answer& answer) noexcept;
  Channel& active_channel(const std::string& body, const char* option);
  // One turn of holding a step: commands in, and the held step published again every
  // kRepublishWhileWaitingNs (`republish_ns`: when next). False on a stop signal.
  bool hold_step_turn(std::int64_t now_ns, std::int64_t& republish_ns) noexcept;
  // What a step's states all say of it.
  struct StateStamp {
    std::uint64_t step = 0;
    double time_s = 0.0;
    std::int64_t step_due_ns = 0;
    std::int64_t stamp_ns = 0;  // the publish stamp
  };
  // Reads the channel's body and writes its state; nullptr when its slot could not be had.
  const BodyState* publish_state(Channel& channel, BodyReading& reading,
                                 const StateStamp& stamp) noexcept;
  // Until a command comes (or `until_ns`): asleep on the waiter, or one sched_yield.
  void wait_for_commands(std::int64_t until_ns) noexcept;
  // Readies waiter_ on every body's commands; false (no waiter) past its capacity.
  bool attach_command_waiter();
  // "ambf/env/base, ambf/env/link1": the active bodies no lockstep client answers for.
  std::string bodies_without_client() const;
  void fill_objects(std::array<WorldObjectPose, kMaxWorldObjects>& out,
                    const std::vector<WorldObjectSpec>& specs,
                    Pose (Simulation::*pose)(std::size_t) const noexcept) const noexcept;

  Simulation& sim_;
  // The channels this process claims through the hub: checked before any publisher
  // below is opened, confirmed once the directory is out.
  std::vector<std::string> claimed_;
  std::vector<Channel> channels_;
  BodyInput input_;  // the command being checked and applied, out of shared memory
  // A body's readings on their way into its state, one per thread writing states.
  std::array<BodyReading, 2> readings_;
  DirectoryPublisher directory_;
  Writer<WorldState> world_;
  Writer<SceneDescription> scene_;        // published once: what a viewer draws
  Writer<ScenePoses> scene_poses_;        // where it is, at display rate
  std::uint32_t scene_joint_values_ = 0;  // joint positions per ScenePoses: fixed by the model
  bool scene_poses_published_ = false;
  // Every step's states again, queued for a recorder, while one reads: a recorder that
  // falls behind the latest-value states catches up from its queue.
  std::string world_instance_;  // the world's name on its channels (and on the tape)
  StepTapeWriter tape_;
  std::uint64_t taped_step_ = ~0ULL;    // a paused world's step is taped once
  std::int64_t step_published_ns_ = 0;  // when the current step's states first went out
  std::int64_t view_next_ns_ = 0;       // when publish_view is due next
  std::unique_ptr<WorldCommandQueue> world_commands_;
  std::uint64_t rejected_ = 0, expiries_ = 0, stale_ = 0;
  bool lockstep_ = false;
  LockstepOptions lockstep_options_;
  std::unique_ptr<SampleWaiter> waiter_;  // the command readers; none: waits poll
  std::uint64_t late_answers_ = 0, dropped_ = 0;
  // Lockstep clients: each pid in the barrier with its number of bodies (room for
  // one per channel, made at construction), and how many pids there are.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> lockstep_pids_;
  std::uint32_t lockstep_client_count_ = 0;
  // Steps taken under command, and those whose command answered the newest state.
  std::uint64_t commanded_steps_ = 0, answered_steps_ = 0, timeliness_step_ = 0;
  WorldClock last_published_;
  // Per soft body (up to kMaxSceneSoftBodies) its surface's two channels.
  struct SoftSurface {
    std::size_t index = 0;  // into model soft bodies
    std::unique_ptr<Writer<SoftBodyMesh>> faces, nodes;
    bool nodes_published = false;
  };
  std::vector<SoftSurface> soft_surfaces_;
};

}  // namespace afhub::physics
