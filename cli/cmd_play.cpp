// `afhub play FILE.mcap`: replays a recording's states into the hub as a physics would,
// for `afhub echo`, `afhub view`, controllers and the DDS bridge to see the run again.
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/startup_wait.hpp"
#include "afhub/record/lockstep_replay.hpp"
#include "afhub/record/player.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "commands.hpp"

namespace afhub::cli {
namespace {

struct PlayCliOptions {
  mcap::PlayOptions play;
  bool fast = false;
  bool into_physics = false;
  double wait_s = 0.0;
};

void warn_if_cut_off(const std::string& file, const std::string& cut_off) {
  if (!cut_off.empty())
    std::fprintf(stderr,
                 "afhub play: warning: %s was cut off (%s): played up to there; `afhub record "
                 "--recover` gives it its index\n",
                 file.c_str(), cut_off.c_str());
}

int run_replay(const PlayCliOptions& options) {
  const mcap::ReplayCheck check =
      mcap::replay_into_physics(options.play.file, [] { return !stop_requested(); });
  warn_if_cut_off(options.play.file, check.cut_off);
  if (check.diverged) {
    std::printf("diverges at step %llu: %s %s (%llu steps and %llu states identical before it)\n",
                static_cast<unsigned long long>(check.step), check.body.c_str(),
                check.field.c_str(), static_cast<unsigned long long>(check.steps),
                static_cast<unsigned long long>(check.states));
    return 1;
  }
  std::printf("reproduced bit-identically: %llu steps, %llu body states compared\n",
              static_cast<unsigned long long>(check.steps),
              static_cast<unsigned long long>(check.states));
  return 0;
}

int run_play(PlayCliOptions& options) {
  if (options.fast) options.play.rate = 0.0;
  install_stop_signal_handlers();
  // A hub lost: the process re-executes, waits for the next hub and plays again from
  // the start (a replay into a physics, of the physics there then).
  survive_hub_loss("afhub play");
  const StartupWait wait(options.wait_s);
  wait.connect_to_hub("play");
  if (options.into_physics) return run_replay(options);
  std::fprintf(stderr, "afhub play: %s into the hub (Ctrl-C stops)\n", options.play.file.c_str());
  const mcap::PlayReport report = mcap::play(options.play, [] { return !stop_requested(); });
  std::fprintf(stderr, "afhub play: published %llu messages in %u complete pass%s\n",
               static_cast<unsigned long long>(report.published), report.passes,
               report.passes == 1 ? "" : "es");
  warn_if_cut_off(options.play.file, report.cut_off);
  if (report.published == 0 && report.passes > 0) {
    const char* where = options.play.start_s > 0.0 || options.play.end_s > 0.0
                            ? " between --start and --end"
                            : (report.cut_off.empty() ? "" : " before it was cut off");
    std::fprintf(stderr,
                 "afhub play: error: %s holds no body or world state%s to replay (commands and "
                 "devices are not replayed; `afhub info %s` tells what it holds)\n",
                 options.play.file.c_str(), where, options.play.file.c_str());
    return 1;
  }
  return report.unmatched_globs > 0 ? 1 : 0;  // a typo in --bodies, said above
}

}  // namespace

void register_play(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<PlayCliOptions>();
  auto* play = app.add_subcommand(
      "play",
      "Replay a recording of `afhub record` into the hub as a physics would (body states, the "
      "world's state, the scene), with its recorded timing; `afhub world` pauses, resumes and "
      "steps it.");
  play->add_option("file", options->play.file, "The .mcap file")
      ->required()
      ->check(CLI::ExistingFile);
  play->add_option("--rate", options->play.rate, "Speed: 2 plays twice as fast, 0.5 half")
      ->capture_default_str();
  play->add_flag("--fast", options->fast, "As fast as possible, ignoring the recorded timing");
  play->add_flag("--loop", options->play.loop, "Start again at the end, until Ctrl-C");
  play->add_option("--start", options->play.start_s,
                   "Seconds into the recording to start from (default 0)");
  play->add_option("--end", options->play.end_s,
                   "Seconds into the recording to end at (default: its end)");
  play->add_option("--bodies", options->play.body_globs,
                   "Body channels to replay, as globs (default: every body recorded)");
  play->add_flag("--commands-into-physics", options->into_physics,
                 "Reproduce a lockstep run: its recorded commands into a new physics of the same "
                 "models (`afhub run ... --lockstep --wait-for 1`), every state compared bit for "
                 "bit with the recording; names the first step that differs (exit 1)");
  play->add_option("--wait", options->wait_s,
                   "Started together with the hub (a launch script): wait up to this many "
                   "seconds for it, saying so once (default 0: fail at once)");
  play->callback([&selected, options] { selected = [options] { return run_play(*options); }; });
}

}  // namespace afhub::cli
