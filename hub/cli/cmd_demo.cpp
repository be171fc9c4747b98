// `afhub demo`: a hub (started if none runs), a process publishing synthetic
// bodies, and a live view of them read through zero-copy channels.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/error.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/stop_signal.hpp"
#include "commands.hpp"

namespace afhub::cli {
namespace {

struct DemoOptions {
  double seconds = 0.0;  // 0: until Ctrl-C
};

pid_t spawn_synth() {
  pid_t pid = fork();
  if (pid < 0) throw Error("cannot start the synthetic publisher: fork failed");
  if (pid == 0) {
    execl("/proc/self/exe", "afhub", "synth", "--namespace", "demo", "--bodies", "3", "--joints",
          "3", "--no-autostart", static_cast<char*>(nullptr));
    std::perror("afhub demo: cannot run afhub synth");
    _exit(127);
  }
  return pid;
}

void draw(CatalogReader& catalog, std::vector<std::unique_ptr<BodyClient>>& clients, bool tty) {
  const BodyList& list = catalog.latest();
  std::string screen = tty ? "\033[H\033[2J" : "";
  screen +=
      "afhub demo: live bodies (Ctrl-C stops; `afhub ls`, `afhub echo demo/body0` in another "
      "shell)\n";
  char line[256];
  std::snprintf(line, sizeof line, "%-16s %9s %9s %9s  %-26s %s\n", "BODY", "RATE_HZ", "STEP",
                "SIM_S", "POSITION_M", "JOINTS_RAD");
  screen += line;
  for (std::uint32_t i = 0; i < list.body_count; ++i) {
    std::string channel(name_of(list.bodies[i].channel));
    if (clients.size() <= i) clients.push_back(std::make_unique<BodyClient>(channel));
    const BodyState* state = clients[i]->latest_state();
    if (!state) continue;
    const Vec3& p = state->pose.position_m;
    std::snprintf(line, sizeof line, "%-16s %9.1f %9llu %9.3f  [%7.3f %7.3f %7.3f]   ",
                  channel.c_str(), list.bodies[i].publish_rate_hz,
                  static_cast<unsigned long long>(state->header.sim_step), state->header.sim_time_s,
                  p.x, p.y, p.z);
    screen += line;
    for (std::uint32_t j = 0; j < state->joint_count; ++j) {
      std::snprintf(line, sizeof line, "%7.3f ", state->joint_positions[j]);
      screen += line;
    }
    screen += "\n";
  }
  std::fputs(screen.c_str(), stdout);
  std::fflush(stdout);
}

int run_demo(const DemoOptions& options) {
  install_stop_signal_handlers();
  connect_to_hub("demo", HubPolicy::kAutostart);
  const pid_t synth = spawn_synth();
  CatalogReader catalog;
  catalog.wait(std::chrono::milliseconds(1000));
  std::vector<std::unique_ptr<BodyClient>> clients;
  const bool tty = isatty(STDOUT_FILENO);
  const auto refresh = std::chrono::milliseconds(tty ? 100 : 1000);
  const auto start = std::chrono::steady_clock::now();
  while (!stop_requested()) {
    if (options.seconds > 0 &&
        std::chrono::steady_clock::now() - start > std::chrono::duration<double>(options.seconds))
      break;
    int status = 0;
    if (waitpid(synth, &status, WNOHANG) == synth) {
      std::fprintf(stderr, "afhub demo: the synthetic publisher exited unexpectedly\n");
      return 1;
    }
    draw(catalog, clients, tty);
    std::this_thread::sleep_for(refresh);
  }
  kill(synth, SIGTERM);
  waitpid(synth, nullptr, 0);
  std::fprintf(stderr, "afhub demo: done. The hub keeps running; stop it with `afhub hub stop`.\n");
  return 0;
}

}  // namespace

void register_demo(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<DemoOptions>();
  auto* demo = app.add_subcommand(
      "demo", "Run the demo: a hub, synthetic bodies published at 1 kHz, and a live view of them.");
  demo->add_option("--seconds", options->seconds,
                   "Stop after this many seconds (default: until Ctrl-C)");
  demo->callback([&selected, options] { selected = [options] { return run_demo(*options); }; });
}

}  // namespace afhub::cli
