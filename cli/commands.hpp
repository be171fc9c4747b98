// The afhub subcommands. Each register_* adds one subcommand to the CLI; when the
// user picks it, `selected` is set to the function that runs it and returns the
// exit code.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace afhub::cli {

using Runner = std::function<int()>;

void register_hub(CLI::App& app, Runner& selected);
void register_ls(CLI::App& app, Runner& selected);
void register_echo(CLI::App& app, Runner& selected);
void register_cmd(CLI::App& app, Runner& selected);
void register_status(CLI::App& app, Runner& selected);
void register_synth(CLI::App& app, Runner& selected);
void register_demo(CLI::App& app, Runner& selected);
void register_check(CLI::App& app, Runner& selected);
void register_convert(CLI::App& app, Runner& selected);
void register_run(CLI::App& app, Runner& selected);
void register_ctl(CLI::App& app, Runner& selected);
void register_top(CLI::App& app, Runner& selected);
void register_bench(CLI::App& app, Runner& selected);
void register_world(CLI::App& app, Runner& selected);
void register_device(CLI::App& app, Runner& selected);
void register_teleop(CLI::App& app, Runner& selected);
void register_view(CLI::App& app, Runner& selected);
void register_bridge(CLI::App& app, Runner& selected);
void register_record(CLI::App& app, Runner& selected);
void register_info(CLI::App& app, Runner& selected);
void register_play(CLI::App& app, Runner& selected);
void register_plot(CLI::App& app, Runner& selected);

}  // namespace afhub::cli
