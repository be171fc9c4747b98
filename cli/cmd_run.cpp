// `afhub run`: load AMBF descriptions (files, a launch file with -l, -a lists, a
// world file) and simulate them in Bullet, each active body on its channels.
#include <cstdio>
#include <fstream>
#include <memory>

#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/physics/mesh_fallback.hpp"
#include "afhub/physics/run_loop.hpp"
#include "afhub/physics/scene_loader.hpp"
#include "afhub/rt/periodic_loop.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/yaml/number_text.hpp"
#include "commands.hpp"
#include "connection_options.hpp"
#include "count_option.hpp"
#include "format.hpp"
#include "gain_options.hpp"
#include "realtime_options.hpp"
#include "scene_options.hpp"

namespace afhub::cli {
namespace {

struct RunCliOptions {
  SceneOptions scene;
  std::string report_file, step_log_file, watchdog_hold, name_space;
  std::string gravity;                       // "x,y,z": over the world's and every file's
  std::vector<std::string> watchdog_bodies;  // "BODY=SECONDS"
  double dt_s = 0.001;
  double watchdog_s = 0.5;
  std::uint64_t steps = 0;
  bool fast = false;
  bool offline = false;
  bool no_autostart = false;
  bool lockstep = false;
  bool spin = false;
  std::uint32_t wait_for = 0;
  double wait_timeout_s = 0.0;
  double client_timeout_ms = 100.0;
  RealtimeOptions realtime;
  bool stop_on_nan = false;
  bool paused = false;
  bool reduced_coordinates = false;
  std::string overrun = "catch-up";
  double max_catch_up_ms = 100.0;
  std::string mesh_fallback = "refuse";
  GainOptions gains;
};

int run_run(const RunCliOptions& options) {
  if (!(options.dt_s >= 1e-5 && options.dt_s <= 0.1))
    throw Error("--dt must be between 0.00001 and 0.1 s, got " + std::to_string(options.dt_s));
  if (!(options.watchdog_s >= physics::SimChannels::kMinWatchdogS &&
        options.watchdog_s <= physics::SimChannels::kMaxWatchdogS))
    throw Error("--watchdog must be 0.002 to 3600 seconds, got " +
                std::to_string(options.watchdog_s));
  if (!(options.client_timeout_ms > 0.0 && options.client_timeout_ms <= 60'000.0))
    throw Error("--client-timeout must be above 0 and at most 60000 ms");
  if (!options.lockstep && options.spin)
    throw Error("--spin needs --lockstep: it is how the physics waits for lockstep answers");
  if (!options.lockstep && options.wait_for > 0)
    throw Error("--wait-for needs --lockstep: it holds the first step for lockstep clients");
  if (!(options.wait_timeout_s >= 0.0 && options.wait_timeout_s <= 1e6))
    throw Error(
        "--wait-timeout must be a number of seconds up to 1e6, 0 (the default) to wait forever");
  if (options.wait_timeout_s > 0.0 && options.wait_for == 0)
    throw Error("--wait-timeout needs --wait-for N: it limits the wait for N lockstep clients");
  if (options.overrun != "catch-up" && options.overrun != "skip")
    throw Error("--overrun takes skip or catch-up, got '" + options.overrun + "'");
  if (options.mesh_fallback != "refuse" && options.mesh_fallback != "box")
    throw Error("--mesh-fallback takes refuse or box, got '" + options.mesh_fallback + "'");
  if (!(options.max_catch_up_ms >= 0.0 && options.max_catch_up_ms <= 10'000.0))
    throw Error("--max-catch-up must be 0 to 10000 ms, got " +
                std::to_string(options.max_catch_up_ms));
  if (!options.step_log_file.empty() && (options.steps == 0 || options.steps > 100'000'000))
    throw Error("--step-log needs --steps N (at most 1e8): the log is sized before the first step");
  LoopOptions realtime;
  set_realtime_options(options.realtime, realtime);
  if (options.offline && (options.lockstep || options.paused || !options.watchdog_hold.empty() ||
                          !options.watchdog_bodies.empty()))
    throw Error(
        "--lockstep, --paused, --watchdog-hold and --watchdog-body need the hub's channels: drop "
        "--offline");
  // "arm/link3=0.002": each body's own watchdog period.
  std::vector<std::pair<std::string, double>> watchdog_bodies;
  for (const std::string& list : options.watchdog_bodies)
    for (const std::string& entry : split_commas(list)) {
      const std::size_t equals = entry.rfind('=');
      const std::optional<double> seconds =
          equals == std::string::npos ? std::nullopt : yaml::parse_finite(entry.substr(equals + 1));
      if (equals == 0 || !seconds)
        throw Error("--watchdog-body takes BODY=SECONDS, e.g. arm/link3=0.002; got '" + entry +
                    "'");
      watchdog_bodies.emplace_back(entry.substr(0, equals), *seconds);
    }
  const physics::SceneRequest request = scene_request(options.scene);
  physics::Model model;
  try {
    model = physics::load_scene(request);
  } catch (const Error& error) {
    std::fprintf(stderr, "%s\n", error.what());  // "file:line:col: error: ..."
    return 1;
  }
  for (const auto& warning : model.warnings) std::fprintf(stderr, "%s\n", warning.c_str());
  apply_gain_options(model, options.gains);  // names as the files give them: before --namespace
  if (!options.name_space.empty()) physics::prefix_channels(model, options.name_space);
  if (!options.gravity.empty()) {
    std::vector<std::string> warnings;
    physics::override_gravity(model, parse_gravity(options.gravity, warnings));
    for (const std::string& warning : warnings) std::fprintf(stderr, "%s\n", warning.c_str());
  }
  model.world.reduced_coordinates = options.reduced_coordinates;

  if (options.mesh_fallback == "box")
    for (const std::string& warning : physics::fall_back_to_boxes(model))
      std::fprintf(stderr, "%s\n", warning.c_str());

  install_stop_signal_handlers();
  std::unique_ptr<physics::Simulation> built;
  try {
    built = std::make_unique<physics::Simulation>(model, options.dt_s);
  } catch (const Error& error) {
    std::fprintf(stderr, "%s\n", error.what());  // a mesh: "file:line:col: error: body ..."
    return 1;
  }
  physics::Simulation& sim = *built;
  for (const std::string& note : sim.parted_overlaps()) std::fprintf(stderr, "%s\n", note.c_str());
  for (const std::string& note : sim.gain_notes()) std::fprintf(stderr, "%s\n", note.c_str());
  for (const auto& warnings : {sim.overlaps_between_files(), sim.joints_outside_limits()})
    for (const std::string& warning : warnings) std::fprintf(stderr, "%s\n", warning.c_str());
  if (options.reduced_coordinates)
    std::fprintf(stderr,
                 "afhub run: %zu of %zu bodies in reduced coordinates, as links of open chains "
                 "on static bodies; the rest in maximal coordinates\n",
                 sim.links_in_reduced_coordinates(), model.bodies.size());
  std::unique_ptr<physics::SimChannels> channels;
  if (!options.offline) {
    // A lost hub: the loop holds (no step, no state out), then the process re-executes,
    // waits for a hub and starts its world again from the model (hub_loss.hpp).
    survive_hub_loss("afhub run");
    connect_to_hub("physics", hub_policy(options.no_autostart));
    channels = std::make_unique<physics::SimChannels>(sim, options.watchdog_s, options.name_space);
    for (const std::string& body : split_commas(options.watchdog_hold))
      channels->hold_on_watchdog(body);
    for (const auto& [body, seconds] : watchdog_bodies) channels->set_watchdog(body, seconds);
    if (options.lockstep) {
      physics::LockstepOptions lockstep;
      lockstep.wait_for = options.wait_for;
      lockstep.wait_timeout_ns = static_cast<std::int64_t>(options.wait_timeout_s * 1e9);
      lockstep.client_timeout_ns = static_cast<std::int64_t>(options.client_timeout_ms * 1e6);
      lockstep.spin = options.spin;
      channels->enable_lockstep(lockstep);
    }
    std::fprintf(stderr, "afhub run: %zu bodies, %zu joints on channels; %s%s at dt %.6g s\n",
                 channels->channel_count(), model.joints.size(),
                 options.fast ? "as fast as possible" : "real time",
                 options.lockstep ? " in lockstep" : "", options.dt_s);
  }
  physics::RunOptions run;
  run.fast = options.fast;
  run.steps = options.steps;
  run.stop_on_nan = options.stop_on_nan;
  run.start_paused = options.paused;
  run.overrun = options.overrun == "skip" ? OverrunPolicy::kSkip : OverrunPolicy::kCatchUp;
  run.max_catch_up_ns = static_cast<std::int64_t>(options.max_catch_up_ms * 1e6);
  run.grant = apply_realtime(realtime, "afhub run");
  physics::RunReport report;
  if (!options.step_log_file.empty()) report.step_log.reserve(options.steps);
  physics::run_loop(sim, channels.get(), run, report);
  // Where the loops held worst: the joint, its pivot gap and the step (`--report` has each
  // joint's).
  if (const std::string worst = physics::worst_joint_summary(report, sim); !worst.empty())
    std::fprintf(stderr, "afhub run: %llu steps; %s\n",
                 static_cast<unsigned long long>(report.steps), worst.c_str());
  if (const std::string nan = physics::nan_summary(sim); !nan.empty()) {
    if (report.nan_detected)
      std::fprintf(stderr,
                   "afhub run: the simulation became NaN or infinite (%s); stopping "
                   "(--stop-on-nan). Lower the gains or --dt, or check masses and inertias\n",
                   nan.c_str());
    else
      std::fprintf(stderr, "afhub run: %s. Lower the gains or --dt, or check masses and inertias\n",
                   nan.c_str());
  }
  if (!options.report_file.empty()) {
    std::ofstream out(options.report_file);
    out << physics::report_json(report, sim);
    out.close();  // its last bytes written now, so that a full disk is said
    if (!out) throw Error("cannot write the report to " + options.report_file);
  }
  if (!options.step_log_file.empty()) {
    std::ofstream out(options.step_log_file);
    out << "begin_ns step_us commands_us publish_us due_ns late\n";
    for (const physics::StepSample& sample : report.step_log)
      out << sample.begin_ns << ' ' << sample.duration_us << ' ' << sample.commands_us << ' '
          << sample.publish_us << ' ' << sample.due_ns << ' ' << sample.late << '\n';
    out.close();
    if (!out) throw Error("cannot write the step log to " + options.step_log_file);
  }
  return report.nan_detected ? 1 : 0;
}

}  // namespace

void register_run(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<RunCliOptions>();
  auto* run = app.add_subcommand(
      "run",
      "Simulate AMBF descriptions in Bullet; every active body publishes its state and reads "
      "its commands on the hub's channels.");
  add_scene_options(run, options->scene,
                    "A world file (gravity, enclosure, lights, cameras, environment)");
  run->add_option(
      "--namespace", options->name_space,
      "Put every body's channels under this prefix (copy/afhub/arm/base), and the world's "
      "(copy/world: `afhub world pause --namespace copy`), to run a second copy of a model "
      "beside the first: a live body has one publisher");
  run->add_option("--gravity", options->gravity,
                  "x,y,z in m/s^2 for the world and every body, over the world file's and the "
                  "model files' `gravity` (by AMBF's rule a file's gravity wins over the world's)");
  add_gain_options(run, options->gains);
  run->add_flag("--reduced-coordinates", options->reduced_coordinates,
                "Simulate each open chain hanging from a static body (an arm on its base) in "
                "joint coordinates, Bullet's multibody: no constraint rows hold it together, "
                "and many arms step in about half the time. Closed loops, free-floating "
                "robots, springs and bodies with actuators stay as they are. A link then "
                "takes no velocity command (docs/performance.md)");
  run->add_option("--dt", options->dt_s, "Fixed step in seconds (default 0.001)");
  run->add_flag("--fast", options->fast, "Step as fast as possible instead of in real time");
  add_count_option(run, "--steps", options->steps,
                   "Stop after this many steps (default: until Ctrl-C)");
  run->add_option("--watchdog", options->watchdog_s,
                  "Seconds without a command before a body's commands fall to zero, and the age "
                  "past which a command is stale and ignored (default 0.5; 0.002 to 3600)");
  run->add_option("--watchdog-body", options->watchdog_bodies,
                  "A body's own watchdog, BODY=SECONDS, comma-separated or repeated: "
                  "--watchdog-body arm/link3=0.002 for a 500 Hz+ haptic device");
  run->add_option("--watchdog-hold", options->watchdog_hold,
                  "Bodies whose joints hold their positions when the watchdog fires, instead of "
                  "zero effort: names or last parts, comma-separated");
  run->add_flag("--lockstep", options->lockstep,
                "Step only when every lockstep client (`afhub ctl ... --lockstep`) has answered "
                "the current step");
  run->add_flag("--spin", options->spin,
                "With --lockstep: poll for the clients' answers with sched_yield instead of "
                "sleeping until one comes (only on a core of its own: under SCHED_FIFO a yield "
                "never lets a client run on that core)");
  add_count_option(run, "--wait-for", options->wait_for,
                   "With --lockstep: hold step 0 until this many lockstep clients joined; says "
                   "every 2 s whom it still waits for");
  run->add_option("--wait-timeout", options->wait_timeout_s,
                  "With --wait-for: give up with an error (exit 1) when the clients have not all "
                  "joined after this many seconds (default 0: wait until Ctrl-C)");
  run->add_option("--client-timeout", options->client_timeout_ms,
                  "With --lockstep: ms a step waits for a client's answer before going ahead "
                  "(default 100); 3 misses in a row drop the client until it answers again");
  run->add_option("--overrun", options->overrun,
                  "After a stall (the process descheduled or stopped): catch-up (the default) "
                  "runs the late steps back to back, at most --max-catch-up of them, skipping "
                  "the rest, each waiting up to a fifth of the period for the controllers in "
                  "phase to answer the step before; skip goes on at the next period, the steps "
                  "missed skipped (no burst, for haptics)");
  run->add_option("--mesh-fallback", options->mesh_fallback,
                  "A body whose collision mesh cannot be used (corrupt, or it crashes or hangs "
                  "the mesh reader): refuse (the default) refuses the model; box makes the body "
                  "collide as a box of its mass and inertia, said once per body");
  run->add_option("--max-catch-up", options->max_catch_up_ms,
                  "With --overrun catch-up: the most simulated time, in ms, made up after a "
                  "stall (default 100; 0 to 10000); a longer stall is skipped");
  add_realtime_options(run, options->realtime, "the physics loop");
  run->add_option("--report", options->report_file,
                  "Write a JSON report at the end (steps, step times, poses, joints)");
  run->add_option("--step-log", options->step_log_file,
                  "Write each step's start (CLOCK_MONOTONIC ns), duration with its states "
                  "published, the body commands read before it and the publishing (us) at the "
                  "end, one line a step (with --steps: the log is sized before the first step)");
  run->add_flag("--offline", options->offline,
                "Simulate without a hub: no channels (for reports and measurements)");
  add_no_autostart_option(run, options->no_autostart);
  run->add_flag("--paused", options->paused,
                "Start paused at step 0 (the model as loaded, published); `afhub world resume` "
                "or `step N` goes on: controllers and `afhub record` join before anything moves");
  run->add_flag("--stop-on-nan", options->stop_on_nan,
                "Stop (exit 1) at the first step that makes a body NaN or infinite, instead of "
                "putting the body back at its last good pose with its commands released");
  run->callback([&selected, options] { selected = [options] { return run_run(*options); }; });
}

}  // namespace afhub::cli
