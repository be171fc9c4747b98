// How a command finds the hub and its world (see connection_options.hpp).
#include "connection_options.hpp"

#include <cstdio>

namespace afhub::cli {

void add_no_autostart_option(CLI::App* command, bool& no_autostart) {
  command->add_flag("--no-autostart", no_autostart,
                    "Fail instead of starting a hub when none runs");
}

HubPolicy hub_policy(bool no_autostart) {
  return no_autostart ? HubPolicy::kRequire : HubPolicy::kAutostart;
}

void add_wait_option(CLI::App* command, double& seconds, const std::string& what) {
  char default_s[32];
  std::snprintf(default_s, sizeof default_s, "%g", seconds);
  const std::string waited = what.empty() ? "it" : "the hub and then " + what;
  command->add_option("--wait", seconds,
                      "Started together with the hub" + (what.empty() ? "" : " and " + what) +
                          " (a launch script), wait up to this many seconds for " + waited +
                          ", saying so once, before failing (default " + default_s +
                          "; 0 fails at once)");
}

void add_world_namespace_option(CLI::App* command, std::string& name_space) {
  command->add_option("--namespace", name_space,
                      "The world of a physics run with `afhub run --namespace NS`");
}

}  // namespace afhub::cli
