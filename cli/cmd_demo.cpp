// `afhub demo`: a hub (started if none runs), `afhub run` simulating the KUKA arm
// of the AMBF models in Bullet, a 200 Hz loop waving its joints through position
// commands, and a live view of every body read through zero-copy channels.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "commands.hpp"

namespace afhub::cli {
namespace {

struct DemoOptions {
  double seconds = 0.0;  // 0: until Ctrl-C
  std::string model = AFHUB_DEMO_MODEL;
};

pid_t spawn_physics(const std::string& model) {
  pid_t pid = fork();
  if (pid < 0) throw Error("cannot start the simulation: fork failed");
  if (pid == 0) {
    execl("/proc/self/exe", "afhub", "run", model.c_str(), "--no-autostart",
          static_cast<char*>(nullptr));
    std::perror("afhub demo: cannot run afhub run");
    _exit(127);
  }
  return pid;
}

// Each joint of the root body follows its own slow sinusoid (position commands).
void wave_joints(BodyClient& root, double t) {
  const BodyState* state = root.latest_state();
  BodyCommand* command = root.loan_command();
  if (!state || !command) return;
  command->joint_count = state->joint_count;
  for (std::uint32_t j = 0; j < state->joint_count; ++j) {
    command->joint_types[j] = JointCommandType::kPosition;
    command->joint_values[j] = 0.6 * std::sin(2.0 * M_PI * 0.2 * t + 0.9 * j);
  }
  root.publish_command(command);
}

void draw(CatalogReader& catalog, std::vector<std::unique_ptr<BodyClient>>& clients, bool tty) {
  const BodyList& list = catalog.latest();
  std::string screen = tty ? "\033[H\033[2J" : "";
  screen +=
      "afhub demo: the KUKA simulated live (Ctrl-C stops; try `afhub ls`, `afhub echo link7`, "
      "`afhub status` in another shell)\n";
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
  if (!std::filesystem::is_regular_file(options.model))
    throw Error("the demo model " + options.model + " is not there; give one with --model FILE");
  connect_to_hub("demo", HubPolicy::kAutostart);
  const pid_t physics = spawn_physics(options.model);
  CatalogReader catalog;
  catalog.wait(std::chrono::milliseconds(1000));
  std::unique_ptr<BodyClient> root;
  std::vector<std::unique_ptr<BodyClient>> clients;
  const bool tty = isatty(STDOUT_FILENO);
  const auto refresh = std::chrono::milliseconds(tty ? 100 : 1000);
  const auto start = std::chrono::steady_clock::now();
  auto next_draw = start;
  while (!stop_requested()) {
    const auto now = std::chrono::steady_clock::now();
    const double t = std::chrono::duration<double>(now - start).count();
    if (options.seconds > 0 && t > options.seconds) break;
    int status = 0;
    if (waitpid(physics, &status, WNOHANG) == physics) {
      std::fprintf(stderr, "afhub demo: the simulation exited unexpectedly\n");
      return 1;
    }
    // The root body (the first in the catalog with joints) carries every joint.
    const BodyList& list = catalog.latest();
    if (!root && list.body_count > 0 && list.bodies[0].joint_count > 0)
      root = std::make_unique<BodyClient>(std::string(name_of(list.bodies[0].channel)));
    if (root) wave_joints(*root, t);
    if (now >= next_draw) {
      draw(catalog, clients, tty);
      next_draw = now + refresh;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  kill(physics, SIGTERM);
  waitpid(physics, nullptr, 0);
  std::fprintf(stderr, "afhub demo: done. The hub keeps running; stop it with `afhub hub stop`.\n");
  return 0;
}

}  // namespace

void register_demo(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<DemoOptions>();
  auto* demo = app.add_subcommand(
      "demo",
      "Run the demo: a hub, the KUKA arm simulated in Bullet at 1 kHz with its joints waving, "
      "and a live view of its bodies.");
  demo->add_option("--model", options->model, "ADF file to simulate (default: the AMBF KUKA)");
  demo->add_option("--seconds", options->seconds,
                   "Stop after this many seconds (default: until Ctrl-C)");
  demo->callback([&selected, options] { selected = [options] { return run_demo(*options); }; });
}

}  // namespace afhub::cli
