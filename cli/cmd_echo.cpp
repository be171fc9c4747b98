// `afhub echo BODY`: prints each new state of a body, as text or JSON lines.
#include <cstdio>
#include <memory>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/stop_signal.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/shm_layout/error.hpp"
#include "commands.hpp"
#include "format.hpp"

namespace afhub::cli {
namespace {

struct EchoOptions {
  std::string body;
  std::uint64_t count = 0;  // 0: until Ctrl-C
  bool json = false;
  double timeout_s = 5.0;
};

int run_echo(const EchoOptions& options) {
  install_stop_signal_handlers();
  connect_to_hub("echo", HubPolicy::kRequire);
  CatalogReader catalog;
  catalog.wait(std::chrono::milliseconds(1000));
  const BodyInfo info = catalog.resolve(options.body);
  BodyClient body(name_of(info.channel));
  std::uint64_t printed = 0;
  std::int64_t last_sample_ns = monotonic_ns();
  while (!stop_requested() && (options.count == 0 || printed < options.count)) {
    const BodyState* state = body.latest_state();
    if (state && body.state_updated()) {
      std::string line = options.json ? state_json(info, *state) : state_text(info, *state);
      std::printf("%s\n", line.c_str());
      std::fflush(stdout);
      ++printed;
      last_sample_ns = monotonic_ns();
    } else if (options.count != 0 && monotonic_ns() - last_sample_ns >
                                         static_cast<std::int64_t>(options.timeout_s * 1e9)) {
      throw Error("no state from " + std::string(name_of(info.channel)) + " for " +
                  std::to_string(options.timeout_s) + " s; is its publisher paused or gone?");
    }
    sleep_until_ns(monotonic_ns() + 200'000);
  }
  return 0;
}

}  // namespace

void register_echo(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<EchoOptions>();
  auto* echo = app.add_subcommand("echo", "Print each new state of a body (text, or JSON lines).");
  echo->add_option("body", options->body, "Body channel name or a unique suffix of it, e.g. 'base'")
      ->required();
  echo->add_option("--count,-n", options->count,
                   "Stop after this many states (default: until Ctrl-C)");
  echo->add_flag("--json", options->json, "One JSON object per line.");
  echo->add_option(
      "--timeout", options->timeout_s,
      "With --count: fail when no new state arrives for this many seconds (default 5)");
  echo->callback([&selected, options] { selected = [options] { return run_echo(*options); }; });
}

}  // namespace afhub::cli
