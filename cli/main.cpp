// afhub: the one command-line front door.
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#include "afhub/shm_layout/error.hpp"
#include "commands.hpp"

namespace {

// The command that ran: "run", or "" before one was parsed.
std::string command(const CLI::App& app) {
  const auto chosen = app.get_subcommands();
  return chosen.empty() ? std::string() : chosen.front()->get_name();
}

// The deepest command parsed: `at` is it, the path its words ("afhub world step").
const CLI::App* deepest_command(const CLI::App& app, std::string& path) {
  const CLI::App* at = &app;
  path = "afhub";
  for (auto chosen = at->get_subcommands(); !chosen.empty(); chosen = at->get_subcommands()) {
    at = chosen.front();
    path += " " + at->get_name();
  }
  return at;
}

// CLI11 says only "A subcommand is required" (for `afhub world bogus` too): name the
// command and the subcommands it has, and what was given instead.
int missing_subcommand(const CLI::App& app) {
  std::string path;
  const CLI::App* at = deepest_command(app, path);
  std::string choices;
  for (const CLI::App* sub : at->get_subcommands({}))
    choices += (choices.empty() ? "" : ", ") + sub->get_name();
  std::string given;
  for (const std::string& word : at->remaining()) given += (given.empty() ? "" : " ") + word;
  std::fprintf(
      stderr, "%s: %s; choose one of: %s (see `%s --help`)\n", path.c_str(),
      given.empty() ? "a subcommand is required" : ("unknown subcommand '" + given + "'").c_str(),
      choices.c_str(), path.c_str());
  return 2;
}

// A command line CLI11 refused (a missing argument, an unknown option, a value out of
// range): said as the command's, with exit code 2 for every such mistake (CLI11's own
// codes ran from 105 to 109, and its line named no command).
int usage_error(const CLI::App& app, const CLI::ParseError& error) {
  std::string path;
  deepest_command(app, path);
  std::fprintf(stderr, "%s: %s (see `%s --help`)\n", path.c_str(), error.what(), path.c_str());
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "afhub: a shared-memory, zero-copy co-simulation hub for robots.\n"
      "Run `afhub <command> --help` for a command's options."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "afhub " AFHUB_VERSION);
  afhub::cli::Runner selected;
  afhub::cli::register_hub(app, selected);
  afhub::cli::register_ls(app, selected);
  afhub::cli::register_echo(app, selected);
  afhub::cli::register_cmd(app, selected);
  afhub::cli::register_world(app, selected);
  afhub::cli::register_status(app, selected);
  afhub::cli::register_synth(app, selected);
  afhub::cli::register_demo(app, selected);
  afhub::cli::register_check(app, selected);
  afhub::cli::register_convert(app, selected);
  afhub::cli::register_run(app, selected);
  afhub::cli::register_ctl(app, selected);
  afhub::cli::register_top(app, selected);
  afhub::cli::register_bench(app, selected);
  afhub::cli::register_device(app, selected);
  afhub::cli::register_teleop(app, selected);
  afhub::cli::register_view(app, selected);
  afhub::cli::register_bridge(app, selected);
  afhub::cli::register_record(app, selected);
  afhub::cli::register_info(app, selected);
  afhub::cli::register_play(app, selected);
  afhub::cli::register_plot(app, selected);
  try {
    app.parse(argc, argv);
  } catch (const CLI::RequiredError& error) {
    if (std::string(error.what()).find("subcommand is required") != std::string::npos)
      return missing_subcommand(app);
    return usage_error(app, error);
  } catch (const CLI::ParseError& error) {
    // --help and --version end the parse too, with code 0.
    return error.get_exit_code() == 0 ? app.exit(error) : usage_error(app, error);
  }
  // A message located in a file says "path:line: error: ..." itself: not "error" twice.
  const auto say = [&](const char* what) {
    std::fprintf(stderr, "afhub %s: %s%s\n", command(app).c_str(),
                 std::strstr(what, ": error: ") ? "" : "error: ", what);
  };
  try {
    return selected ? selected() : 2;
  } catch (const afhub::Stopped& stopped) {
    std::fprintf(stderr, "afhub %s: %s\n", command(app).c_str(), stopped.what());
    return 0;
  } catch (const std::exception& error) {
    // afhub's own messages, and a library's said as they are: never std::terminate.
    say(error.what());
    return 1;
  } catch (...) {
    std::fprintf(stderr, "afhub %s: error: an unknown exception\n", command(app).c_str());
    return 1;
  }
}
