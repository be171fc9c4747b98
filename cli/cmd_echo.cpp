// `afhub echo BODY`: prints each new state of a body, as text or JSON lines.
#include <cmath>
#include <cstdio>
#include <memory>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/startup_wait.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "commands.hpp"
#include "connection_options.hpp"
#include "count_option.hpp"
#include "format.hpp"
#include "time_options.hpp"

namespace afhub::cli {
namespace {

struct EchoOptions {
  std::string body;
  std::uint64_t count = 0;  // 0: until Ctrl-C
  bool json = false;
  double timeout_s = 5.0;
  double wait_s = 0.0;   // for the hub and the body to appear (a script racing a start)
  std::string fields;    // empty: all in JSON, pose, twist and joints in text
  double rate_hz = 0.0;  // 0: every new state
};

// Prints each new payload `reader` receives with `render`, at most one per min_gap_ns
// of publish stamps, until a stop or options.count lines.
template <class T, class Render>
void print_each(LatestReader<T>& reader, const std::string& channel, const EchoOptions& options,
                std::int64_t min_gap_ns, const Render& render) {
  std::uint64_t printed = 0;
  std::int64_t last_sample_ns = monotonic_ns();
  std::int64_t last_printed_stamp_ns = 0;
  while (!stop_requested() && (options.count == 0 || printed < options.count)) {
    const T* payload = reader.latest();
    if (payload && reader.updated()) {
      last_sample_ns = monotonic_ns();
      if (printed > 0 && payload->header.publish_stamp_ns - last_printed_stamp_ns < min_gap_ns) {
        sleep_until_ns(monotonic_ns() + 200'000);
        continue;
      }
      last_printed_stamp_ns = payload->header.publish_stamp_ns;
      std::printf("%s\n", render(*payload).c_str());
      std::fflush(stdout);
      ++printed;
    } else if (options.count != 0 && monotonic_ns() - last_sample_ns >
                                         static_cast<std::int64_t>(options.timeout_s * 1e9)) {
      throw Error("no state from " + channel + " for " + yaml::number_text(options.timeout_s) +
                  " s; is its publisher paused or gone?");
    }
    sleep_until_ns(monotonic_ns() + 200'000);
  }
}

int run_echo(const EchoOptions& options) {
  // Rate limited by the states' publish stamps: printed states are at least a period apart.
  const std::int64_t min_gap_ns =
      options.rate_hz == 0.0 ? 0 : period_ns_of_rate(options.rate_hz, "--rate (0: every state)");
  ns_of_seconds(options.timeout_s, "--timeout", 0.001);
  const StateFields fields = !options.fields.empty() ? parse_state_fields(options.fields)
                             : options.json          ? StateFields{}
                                                     : default_text_fields();
  install_stop_signal_handlers();
  survive_hub_loss("afhub echo");
  const StartupWait wait(options.wait_s);
  wait.connect_to_hub("echo");
  const BodyEntry entry = wait.wait_for_body(options.body, "afhub echo");
  const std::string channel(name_of(entry.info.channel));
  if (entry.info.kind == ChannelKind::kDevice) {
    if (!options.fields.empty())
      throw Error("--fields chooses among a body's fields; " + channel +
                  " is a device, whose state is printed whole");
    LatestReader<DeviceState> device(body_state_channel(channel));
    print_each(device, channel, options, min_gap_ns, [&](const DeviceState& state) {
      return options.json ? device_state_json(entry, state) : device_state_text(entry, state);
    });
    return 0;
  }
  LatestReader<BodyState> states(body_state_channel(channel));
  print_each(states, channel, options, min_gap_ns, [&](const BodyState& state) {
    return options.json ? state_json(entry, state, fields) : state_text(entry, state, fields);
  });
  return 0;
}

}  // namespace

void register_echo(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<EchoOptions>();
  auto* echo = app.add_subcommand(
      "echo",
      "Print each new state of a body, one line each: step, time, position, orientation "
      "(quaternion x y z w), twist and joint positions, or the --fields asked for (--json: JSON "
      "lines).");
  echo->add_option("body", options->body, "Body channel name or a unique suffix of it, e.g. 'base'")
      ->required();
  add_count_option(echo, "--count,-n", options->count,
                   "Stop after this many states (default: until Ctrl-C)");
  echo->add_flag("--json", options->json, "One JSON object per line.");
  echo->add_option("--fields", options->fields,
                   std::string("The parts of each state to show, comma-separated: ") +
                       kStateFieldNames +
                       " (default: pose,twist,joints in text, all in JSON; step and time always)");
  echo->add_option("--rate", options->rate_hz,
                   "Print at most this many states per second (by their publish stamps; default: "
                   "every new state)");
  add_wait_option(echo, options->wait_s, "the body");
  echo->add_option(
      "--timeout", options->timeout_s,
      "With --count: fail when no new state arrives for this many seconds (default 5)");
  echo->callback([&selected, options] { selected = [options] { return run_echo(*options); }; });
}

}  // namespace afhub::cli
