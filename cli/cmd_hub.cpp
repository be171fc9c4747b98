// `afhub hub` runs the hub in the foreground; `afhub hub stop` stops a running one.
#include "afhub/hub/hub_daemon.hpp"
#include "commands.hpp"

namespace afhub::cli {

void register_hub(CLI::App& app, Runner& selected) {
  auto* hub = app.add_subcommand(
      "hub",
      "Run the hub daemon in the foreground: iceoryx RouDi with afhub's mempools, the body "
      "catalog and health. One per machine; Ctrl-C or SIGTERM stops it.");
  auto* stop = hub->add_subcommand("stop", "Stop the running hub (SIGTERM, waits up to 5 s).");
  hub->require_subcommand(0, 1);
  hub->callback([&selected, stop] {
    if (stop->parsed())
      selected = [] { return stop_hub(); };
    else
      selected = [] { return run_hub_daemon(); };
  });
}

}  // namespace afhub::cli
