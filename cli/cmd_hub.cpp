// `afhub hub` runs the hub in the foreground; `afhub hub stop` stops a running one.
#include <cstdio>
#include <memory>

#include "afhub/hub/hub_daemon.hpp"
#include "commands.hpp"

namespace afhub::cli {
namespace {

struct HubCliOptions {
  std::string mempool_file;
  std::vector<std::string> pools;
  bool bench_pools = false;
  bool dry_run = false;
  bool force = false;  // stop: even with processes attached
  std::string group;
};

int run_hub(const HubCliOptions& cli) {
  std::vector<MempoolSpec> extra;
  if (!cli.mempool_file.empty())
    for (const MempoolSpec& pool : read_mempool_file(cli.mempool_file)) extra.push_back(pool);
  for (const std::string& text : cli.pools) extra.push_back(parse_mempool(text));
  HubOptions options;
  options.mempools = merge_mempools(
      cli.bench_pools ? with_bench_pools(default_mempools()) : default_mempools(), extra);
  options.group = cli.group;
  if (cli.dry_run) {
    std::printf("payload bytes  chunks  holds\n");
    for (const MempoolSpec& pool : options.mempools)
      std::printf("%13u  %6u  %s\n", pool.payload_bytes, pool.chunk_count, pool.holds.c_str());
    return 0;
  }
  return run_hub_daemon(options);
}

}  // namespace

void register_hub(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<HubCliOptions>();
  auto* hub = app.add_subcommand(
      "hub",
      "Run the hub daemon in the foreground: iceoryx RouDi with afhub's mempools, the body "
      "catalog and health. One per machine; Ctrl-C or SIGTERM stops it.");
  hub->add_option("--mempools", options->mempool_file,
                  "File of extra or resized mempools, one '<payload bytes> <chunk count>' per "
                  "line ('#' comments); a size already there gets the new count")
      ->check(CLI::ExistingFile);
  hub->add_option("--pool", options->pools,
                  "An extra or resized mempool as BYTES:COUNT (repeatable), e.g. 65536:32");
  hub->add_flag("--bench-pools", options->bench_pools,
                "Add the pools `afhub bench` needs (1 KiB to 1 MiB samples, 20 MiB)");
  hub->add_flag("--dry-run", options->dry_run, "Print the mempools the hub would have, and exit");
  hub->add_option("--group", options->group,
                  "Let this group's members use the hub (its shared memory and socket); by "
                  "default only the hub's user and its own group can");
  auto* stop = hub->add_subcommand(
      "stop",
      "Stop the running hub (SIGTERM, waits up to 15 s). With processes attached it lists them "
      "and stops only with --force.");
  stop->add_flag("--force", options->force, "Stop the hub even with processes attached");
  hub->require_subcommand(0, 1);
  hub->callback([&selected, stop, options] {
    if (stop->parsed())
      selected = [options] { return stop_hub(options->force); };
    else
      selected = [options] { return run_hub(*options); };
  });
}

}  // namespace afhub::cli
