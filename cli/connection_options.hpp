// The options of how a command finds the hub and its world, each added by one function:
// --no-autostart (run, synth), --wait (ctl, teleop, echo, device run and force) and
// --namespace of a world (world, view).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "afhub/hub/hub_presence.hpp"

namespace afhub::cli {

// --no-autostart: fail instead of starting a hub; hub_policy() says which.
void add_no_autostart_option(CLI::App* command, bool& no_autostart);
HubPolicy hub_policy(bool no_autostart);

// --wait SECONDS (afhub/hub/startup_wait.hpp), for the hub and then `what` ("the body";
// empty: the hub alone); its help gives `seconds` as the default.
void add_wait_option(CLI::App* command, double& seconds, const std::string& what);

// --namespace NS: the world of a physics run with `afhub run --namespace NS`.
void add_world_namespace_option(CLI::App* command, std::string& name_space);

}  // namespace afhub::cli
