// `afhub top`: a live table of every loop (controllers, the physics) with its rate,
// wake-up jitter percentiles, compute time, overruns and late commands.
#include <unistd.h>

#include <cstdio>
#include <memory>
#include <thread>

#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/loop_stats_reader.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "commands.hpp"
#include "loop_table.hpp"

namespace afhub::cli {
namespace {

struct TopOptions {
  bool once = false;
  bool json = false;
};

int run_top(const TopOptions& options) {
  install_stop_signal_handlers();
  if (!options.once && !options.json) survive_hub_loss("afhub top");
  connect_to_hub("top", HubPolicy::kRequire);
  LoopStatsReader reader;
  std::vector<LoopStats> loops = reader.all(std::chrono::seconds(2));
  for (;;) {
    if (options.json) {
      JsonWriter json;
      json.begin_object().key("loops");
      loop_json(json, loops);
      json.end_object();
      std::printf("%s\n", json.str().c_str());
    } else {
      // Clear the terminal; into a pipe or a file, one table after another.
      if (!options.once && isatty(STDOUT_FILENO)) std::printf("\x1b[H\x1b[2J");
      std::printf("%zu loops%s\n%s", loops.size(), options.once ? "" : " (Ctrl-C to quit)",
                  loop_table(loops).c_str());
    }
    std::fflush(stdout);
    if (options.once || options.json) return 0;
    for (int i = 0; i < 10 && !stop_requested(); ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    if (stop_requested()) return 0;
    loops = reader.latest();
  }
}

}  // namespace

void register_top(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<TopOptions>();
  auto* top = app.add_subcommand(
      "top",
      "Live table of every loop: rate, wake-up jitter, compute time, overruns, late commands.");
  top->add_flag("--once", options->once, "Print the table once and exit");
  top->add_flag("--json", options->json, "Print one JSON object and exit");
  top->callback([&selected, options] { selected = [options] { return run_top(*options); }; });
}

}  // namespace afhub::cli
