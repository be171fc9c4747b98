// `afhub bench`: end-to-end latency and jitter, afhub beside Cyclone DDS, Unix
// sockets and ROS 1, and a 1 kHz loop beside cyclictest (see docs/bench.md).
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "afhub/bench/bench.hpp"
#include "afhub/bench/bodies_bench.hpp"
#include "afhub/bench/wake_bench.hpp"
#include "afhub/shm_layout/error.hpp"
#include "commands.hpp"
#include "count_option.hpp"
#include "example_models.hpp"
#include "format.hpp"

namespace afhub::cli {
namespace {

struct BenchCliOptions {
  bool quick = false, touch = false;
  std::string transports, json_file, plot_file, model, body = "arm/base";
  std::uint32_t rounds = 0, pings = 0;
  double loop_seconds = -1.0;
  // The peer process the bench starts for each transport.
  std::string peer, session;
  int peer_cpu = -1;
};

void write_file(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  out.close();
  if (!out) throw Error("cannot write " + path);
}

int run_bench(const BenchCliOptions& cli) {
  if (!cli.peer.empty()) return bench::run_peer(cli.peer, cli.session, cli.peer_cpu, cli.touch);
  bench::BenchOptions options;
  if (cli.quick) options = bench::quick_options(options);
  if (!cli.transports.empty()) options.transports = split_commas(cli.transports);
  if (cli.rounds > 0) options.rounds = cli.rounds;
  if (cli.pings > 0) options.pings_per_round = cli.pings;
  if (cli.loop_seconds >= 0.0) options.loop_seconds = cli.loop_seconds;
  if (options.loop_seconds > 0.0 && options.loop_seconds < 2.0)
    throw Error("--loop-seconds must be 0 (skip the loop) or at least 2");
  options.model = cli.model.empty() ? example_model("arm7.yaml")
                                    : std::filesystem::path(cli.model).lexically_normal().string();
  options.body = cli.body;
  options.touch = cli.touch;

  bench::BenchResults results;
  results.machine = bench::read_machine_info();
  results.options = options;
  bench::start_bench_hub_if_none();
  bench::run_ping_pong(options, results);
  if (options.loop_seconds > 0.0)
    bench::run_loop_bench(options, results.loop);
  else
    results.loop.skipped = "--loop-seconds 0";
  std::printf("afhub bench on %s (%u cores, %.0f GiB), %s, %s\n\n", results.machine.cpu.c_str(),
              results.machine.cores, results.machine.memory_gib, results.machine.kernel.c_str(),
              results.machine.date.c_str());
  std::printf("%s", bench::results_table(results).c_str());
  if (!cli.json_file.empty()) write_file(cli.json_file, bench::results_json(results));
  if (!cli.plot_file.empty()) bench::write_plot(results, cli.plot_file);
  const std::vector<std::string> failures = bench::failures(results);
  for (const std::string& failure : failures)
    std::fprintf(stderr, "afhub bench: FAILED: %s\n", failure.c_str());
  return failures.empty() ? 0 : 1;
}

struct DdsBenchOptions {
  bool quick = false;
  std::string out = "dds-bench";
};

// bench/dds_bridge.sh of the source tree this afhub was built from, with this build.
int run_dds_bench(const DdsBenchOptions& options) {
  const std::filesystem::path script =
      std::filesystem::path(AFHUB_SOURCE_DIR) / "bench/dds_bridge.sh";
  const std::string build =
      std::filesystem::read_symlink("/proc/self/exe").parent_path().parent_path();
  if (!std::filesystem::exists(script) ||
      !std::filesystem::exists(std::filesystem::path(build) / "bin/afhub-dds-bench"))
    throw Error("afhub bench dds runs from a build tree (it needs " + script.string() +
                " and bin/afhub-dds-bench beside this afhub)");
  std::vector<std::string> args{"bash", script.string()};
  if (options.quick) args.push_back("--quick");
  args.push_back(build);
  args.push_back(options.out);
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  // The script becomes this process (its output, exit code and Ctrl-C are the
  // command's): an exec, not a spawn, and this process has no hub threads yet.
  execv("/bin/bash", argv.data());
  throw Error(std::string("cannot run /bin/bash: ") + std::strerror(errno));
}

struct WakeBenchOptions {
  bool quick = false;
  std::uint32_t rounds = 0;
  double seconds = 1.0;
  int peer = -1;  // the bench's own loop processes
};

int run_wake_bench(const WakeBenchOptions& cli) {
  if (!(cli.seconds >= 0.1 && cli.seconds <= 3600.0))
    throw Error("--seconds takes 0.1 to 3600 seconds per setting and round");
  if (cli.peer >= 0) return bench::run_wake_peer(static_cast<std::size_t>(cli.peer), cli.seconds);
  bench::WakeOptions options;
  options.seconds = cli.seconds;
  options.rounds = cli.rounds > 0 ? cli.rounds : cli.quick ? 3 : 10;
  std::printf("%s", bench::wake_table(bench::run_wake_bench(options)).c_str());
  return 0;
}

struct BodiesBenchOptions {
  bench::BodiesOptions bench;
  bool quick = false;
};

int run_bodies_bench(BodiesBenchOptions cli) {
  bench::BodiesOptions& options = cli.bench;
  if (cli.quick) options.seconds = 5.0;
  if (options.arms < 1 || options.arms > 500 || options.links < 2 || options.links > 16)
    throw Error("--arms takes 1 to 500 and --links 2 to 16");
  // The physics' step log of the run is sized, and locked in memory, before it starts.
  if (!(options.seconds >= 2.0 && options.seconds <= 600.0))
    throw Error("--seconds takes 2 to 600");
  bench::start_bench_hub_if_none();
  const bench::BodiesResult result = bench::run_bodies_bench(options);
  std::printf("%s", bench::bodies_table(options, result).c_str());
  const std::vector<std::string> failures = bench::bodies_failures(result);
  for (const std::string& failure : failures)
    std::fprintf(stderr, "afhub bench: FAILED: %s\n", failure.c_str());
  return failures.empty() ? 0 : 1;
}

}  // namespace

void register_bench(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<BenchCliOptions>();
  auto* bench = app.add_subcommand(
      "bench",
      "Measure end-to-end latency over afhub, Cyclone DDS, Unix sockets and ROS 1 (64 B to "
      "1 MiB), and a 1 kHz controller's jitter against the physics beside cyclictest.");
  bench->add_flag("--quick", options->quick, "A shorter run: about 30 s instead of 2.5 min");
  bench->add_flag("--touch", options->touch,
                  "Every sender writes every byte of its message and every receiver reads every "
                  "byte (checked), rather than the stamps alone");
  bench->add_option("--json", options->json_file, "Write every distribution to this JSON file");
  bench->add_option("--plot", options->plot_file,
                    "Draw latency CDFs and the loop's jitter histogram into this PNG (gnuplot)");
  bench->add_option(
      "--transports", options->transports,
      "Transports to compare, comma-separated (default "
      "afhub,afhub-slot,shm-floor,dds,dds-shm,uds,ros1; shm-floor: bare shared memory, the "
      "machine's floor; dds-shm: Cyclone DDS with its shared memory through the hub)");
  add_count_option(bench, "--rounds", options->rounds, "Interleaved rounds (default 20, quick 5)");
  add_count_option(bench, "--pings", options->pings,
                   "Round trips per transport, size and round (default 500, quick 200)");
  bench->add_option("--loop-seconds", options->loop_seconds,
                    "Length of the 1 kHz loop (default 60, quick 20; 0 skips it)");
  bench->add_option("--model", options->model,
                    "ADF model for the loop (default: the example arm, arm7.yaml)");
  bench->add_option("--body", options->body,
                    "The body the loop's controller commands (default base)");
  bench->add_option("--peer", options->peer)->group("");  // the bench's own peer processes
  bench->add_option("--session", options->session)->group("");
  bench->add_option("--peer-cpu", options->peer_cpu)->group("");
  auto dds_options = std::make_shared<DdsBenchOptions>();
  auto* dds = bench->add_subcommand(
      "dds",
      "The DDS bridge between two network namespaces joined by a veth (needs root: ip netns, "
      "mount namespaces, tc): 1 KiB round trips through two bridges (asleep, with idle CPUs "
      "polling by --cpu-wake-latency 0, and polling with --spin) beside Cyclone DDS alone, "
      "and 400 bodies at 1 kHz exported (CPU per 1000 states, allocations, overload). Runs "
      "bench/dds_bridge.sh of the source tree; from a build tree only.");
  dds->add_flag("--quick", dds_options->quick, "A shorter run: about 40 s instead of 1.5 min");
  dds->add_option("--out", dds_options->out,
                  "Folder for the round trips, the reader's seconds and summary.txt (default "
                  "dds-bench); bench/dds_bridge_plot.sh draws them");
  dds->callback([&selected, dds_options] {
    selected = [dds_options] { return run_dds_bench(*dds_options); };
  });
  auto wake_options = std::make_shared<WakeBenchOptions>();
  auto* wake = bench->add_subcommand(
      "wake",
      "A 1 kHz loop's wake-up latency under each real-time setting of run, ctl, teleop and "
      "device run: the normal scheduler with the default timer slack and with afhub's, "
      "--cpu-wake-latency 0, --fifo 80, and both; each in its own process, in interleaved "
      "rounds. SCHED_FIFO and the wake-up limit need root (refused settings are said).");
  wake->add_flag("--quick", wake_options->quick, "3 rounds instead of 10");
  add_count_option(wake, "--rounds", wake_options->rounds, "Interleaved rounds (default 10)");
  wake->add_option("--seconds", wake_options->seconds, "Seconds per setting and round (default 1)");
  wake->add_option("--peer", wake_options->peer)->group("");
  wake->callback([&selected, wake_options] {
    selected = [wake_options] { return run_wake_bench(*wake_options); };
  });
  auto bodies_options = std::make_shared<BodiesBenchOptions>();
  auto* bodies = bench->add_subcommand(
      "bodies",
      "A world of many bodies at 1 kHz across processes: `afhub run` on a generated scene of "
      "arms (125 of 8 links: a thousand bodies) and one controller process commanding every "
      "body each period, in phase with the physics. Each step's commands, physics and "
      "publishing as the physics timed them, and the commands in time.");
  auto* quick = bodies->add_flag("--quick", bodies_options->quick, "5 s measured instead of 20");
  bodies->add_option("--arms", bodies_options->bench.arms, "Arms in the scene (default 125)");
  bodies->add_option("--links", bodies_options->bench.links, "Links per arm (default 8)");
  bodies->add_flag("--reduced-coordinates", bodies_options->bench.reduced_coordinates,
                   "Run the physics with --reduced-coordinates: each arm a multibody");
  bodies
      ->add_option("--seconds", bodies_options->bench.seconds,
                   "Seconds measured (default 20, at most 600)")
      ->excludes(quick);
  bodies->callback([&selected, bodies_options] {
    selected = [bodies_options] { return run_bodies_bench(*bodies_options); };
  });
  bench->callback([&selected, options, dds, wake, bodies] {
    if (dds->parsed() || wake->parsed() || bodies->parsed())
      return;  // CLI11 runs the parent's callback after the subcommand's
    selected = [options] { return run_bench(*options); };
  });
}

}  // namespace afhub::cli
