// `afhub demo`: a hub (started if none runs), `afhub run` simulating the project's
// example scene in Bullet (the 7-DOF arm, the remote-centre-of-motion arm and the
// gripper, with the world's floor, lights and cameras), a 200 Hz loop moving their
// joints through position commands, and a live view of every body read through
// zero-copy channels; beside it `afhub view` serves the scene to a browser, at the URL
// the demo prints (`--no-view`: no viewer). `--model FILE` simulates another model
// and waves its root.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/rt/process_spawn.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "commands.hpp"
#include "example_models.hpp"
#include "time_options.hpp"

namespace afhub::cli {
namespace {

// How long the physics may take to load its scene and show a body in the catalog.
constexpr std::chrono::seconds kSceneTimeout{120};

struct DemoOptions {
  double seconds = 0.0;  // 0: until Ctrl-C
  std::string model;     // empty: the example scene
  bool view = true;
  bool open_browser = true;
  int view_port = 8080;
};

// One commanded joint of the example scene: center + amplitude * sin(2 pi t / period + phase).
struct JointMotion {
  double center, amplitude, period_s, phase;
};
// A root body and the motions of its first joints, in the body's joint order.
struct BodyMotion {
  const char* body;
  std::vector<JointMotion> joints;
};

// The example scene's choreography, within each joint's limits (examples/models).
const std::vector<BodyMotion>& example_scene_motions() {
  static const std::vector<BodyMotion> motions = {
      {"afhub/arm/base",
       {{0, 0.8, 8, 0},
        {0, 0.5, 6, 1},
        {0, 0.5, 7, 2},
        {-0.6, 0.4, 5, 0},
        {0, 0.6, 4, 1},
        {0.3, 0.4, 5, 2},
        {0, 1.0, 3, 0}}},
      // Yaw, pitch about the remote centre, insertion; the loop joints after them are free.
      {"afhub/rcm/base", {{0, 0.5, 6, 0}, {0, 0.4, 5, 1}, {0.075, 0.06, 4, 0}}},
      {"afhub/gripper/palm", {{0.015, 0.014, 2, 0}, {0.015, 0.014, 2, 0}}},
  };
  return motions;
}

// Starts `afhub arguments...`; its stdout goes to `stdout_fd` when that is not -1.
pid_t spawn_afhub(const std::vector<std::string>& arguments, int stdout_fd = -1) {
  std::vector<std::string> argv{this_executable()};
  argv.insert(argv.end(), arguments.begin(), arguments.end());
  SpawnOptions options;
  options.stdout_fd = stdout_fd;
  return spawn_process(argv, options);
}

pid_t spawn_physics(const std::vector<std::string>& run_arguments) {
  std::vector<std::string> arguments{"run"};
  arguments.insert(arguments.end(), run_arguments.begin(), run_arguments.end());
  arguments.push_back("--no-autostart");
  return spawn_afhub(arguments);
}

// `afhub view` beside the demo, and the URL it serves (what it prints first).
struct Viewer {
  pid_t pid = -1;
  int output = -1;  // kept open: the viewer's stdout must not break
  std::string url;
};

Viewer start_viewer(int port) {
  Viewer viewer;
  int pipe_ends[2];
  if (pipe2(pipe_ends, O_CLOEXEC) != 0) throw Error("cannot start the viewer: pipe failed");
  viewer.pid = spawn_afhub({"view", "--port", std::to_string(port)}, pipe_ends[1]);
  close(pipe_ends[1]);
  viewer.output = pipe_ends[0];
  // Its first line names the URL; it comes within a second unless the viewer failed
  // (then its error is on the shared stderr).
  std::string said;
  const std::regex url("http://[^ ]+/");
  std::smatch match;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!std::regex_search(said, match, url) && std::chrono::steady_clock::now() < until) {
    pollfd ready{viewer.output, POLLIN, 0};
    if (poll(&ready, 1, 100) <= 0) continue;
    char text[256];
    const ssize_t n = read(viewer.output, text, sizeof text);
    if (n <= 0) break;  // the viewer exited
    said.append(text, static_cast<std::size_t>(n));
  }
  if (std::regex_search(said, match, url)) viewer.url = match[0];
  return viewer;
}

// At a desktop (a display and xdg-open), the user's browser on `url`; elsewhere (ssh,
// CI) the printed URL is the way in.
void open_browser(const std::string& url) {
  if (!std::getenv("DISPLAY") && !std::getenv("WAYLAND_DISPLAY")) return;
  SpawnOptions options;
  options.search_path = true;
  options.detached = true;  // however long the browser takes, and whatever it says
  options.output_path = "/dev/null";
  try {
    spawn_process({"xdg-open", url}, options);
  } catch (const Error& error) {
    std::fprintf(stderr, "afhub demo: cannot open a browser (%s); open the URL yourself\n",
                 error.what());
  }
}

void stop_viewer(Viewer& viewer) {
  if (viewer.pid <= 0) return;
  kill(viewer.pid, SIGTERM);
  waitpid(viewer.pid, nullptr, 0);
  close(viewer.output);
  viewer.pid = -1;
}

// Position commands for a body's first joints, following `motion`.
void move_joints(BodyClient& body, const std::vector<JointMotion>& motion, double t) {
  BodyCommand* command = body.loan_command(static_cast<std::uint32_t>(motion.size()));
  if (!command) return;
  for (std::size_t j = 0; j < motion.size(); ++j) {
    const JointMotion& m = motion[j];
    command->joints[j].type = JointCommandType::kPosition;
    command->joints[j].value =
        m.center + m.amplitude * std::sin(2.0 * M_PI * t / m.period_s + m.phase);
  }
  body.publish_command(command);
}

// Another model: every joint of its root body on its own slow sinusoid.
std::vector<JointMotion> wave_every_joint(std::uint32_t joint_count) {
  std::vector<JointMotion> motion;
  for (std::uint32_t j = 0; j < joint_count; ++j) motion.push_back({0, 0.6, 5, 0.9 * j});
  return motion;
}

void draw(CatalogReader& catalog, std::vector<std::unique_ptr<BodyClient>>& clients, bool tty,
          const std::string& url) {
  const BodyList& list = catalog.latest();
  std::string screen = tty ? "\033[H\033[2J" : "";
  // A body of the model shown (`--model`: another than the arm's link7).
  const std::string echo =
      list.body_count ? "`afhub echo " + std::string(name_of(list.bodies[0].channel)) + "`, " : "";
  screen += "afhub demo: simulated live (Ctrl-C stops; try `afhub ls`, " + echo +
            "`afhub status` in another shell)\n";
  if (!url.empty()) screen += "afhub demo: see it in a browser: " + url + "\n";
  char line[256];
  std::snprintf(line, sizeof line, "%-28s %9s %9s %9s  %-26s %s\n", "BODY", "RATE_HZ", "STEP",
                "SIM_S", "POSITION_M", "JOINTS_RAD");
  screen += line;
  for (std::uint32_t i = 0; i < list.body_count; ++i) {
    std::string channel(name_of(list.bodies[i].channel));
    if (clients.size() <= i) clients.push_back(std::make_unique<BodyClient>(channel));
    const BodyState* state = clients[i]->latest_state();
    if (!state) continue;
    const Vec3& p = state->pose.position_m;
    // Not measured yet ("-", as `afhub ls` says it), not 0 Hz.
    std::snprintf(line, sizeof line, "%-28s %9s %9llu %9.3f  [%7.3f %7.3f %7.3f]   ",
                  channel.c_str(), rate_text(list.bodies[i].publish_rate_hz).c_str(),
                  static_cast<unsigned long long>(state->header.sim_step), state->header.sim_time_s,
                  p.x, p.y, p.z);
    screen += line;
    for (std::uint32_t j = 0; j < state->joint_count; ++j) {
      std::snprintf(line, sizeof line, "%7.3f ", state->joints[j].position);
      screen += line;
    }
    screen += "\n";
  }
  std::fputs(screen.c_str(), stdout);
  std::fflush(stdout);
}

int run_demo(const DemoOptions& options) {
  ns_of_seconds(options.seconds, "--seconds (0: until Ctrl-C)");  // -1 ran for good
  install_stop_signal_handlers();
  std::vector<std::string> run_arguments;
  if (options.model.empty()) {
    run_arguments = {"--launch", example_model("launch.yaml"), "-l", "0,1,2"};
  } else {
    if (!std::filesystem::is_regular_file(options.model))
      throw Error("the demo model " + options.model + " is not a file; give one with --model FILE");
    run_arguments = {options.model};
  }
  connect_to_hub("demo", HubPolicy::kAutostart);
  const pid_t physics = spawn_physics(run_arguments);
  Viewer viewer;
  if (options.view) {
    viewer = start_viewer(options.view_port);
    if (viewer.url.empty())
      std::fprintf(stderr,
                   "afhub demo: the viewer did not start (see above); the demo goes on without "
                   "it. Try another --view-port, or --no-view.\n");
    else
      std::printf("afhub demo: the viewer: %s\n", viewer.url.c_str());
    if (!viewer.url.empty() && options.open_browser) open_browser(viewer.url);
    std::fflush(stdout);
  }
  CatalogReader catalog;
  catalog.wait(std::chrono::milliseconds(1000));
  // The bodies the demo moves, opened once they are in the catalog.
  std::vector<std::pair<std::unique_ptr<BodyClient>, std::vector<JointMotion>>> movers;
  std::vector<std::unique_ptr<BodyClient>> clients;
  const bool tty = isatty(STDOUT_FILENO);
  const auto refresh = std::chrono::milliseconds(tty ? 100 : 1000);
  const auto start = std::chrono::steady_clock::now();
  // --seconds counts from the scene's bodies in the catalog: a loaded machine may take
  // seconds to load the meshes, and the demo's seconds are seconds of simulation shown.
  std::optional<std::chrono::steady_clock::time_point> live;
  auto next_draw = start;
  std::uint32_t drawn_bodies = 0;
  while (!stop_requested()) {
    const auto now = std::chrono::steady_clock::now();
    const double t = std::chrono::duration<double>(now - start).count();
    if (options.seconds > 0 && live &&
        std::chrono::duration<double>(now - *live).count() > options.seconds)
      break;
    if (!live && now - start > kSceneTimeout) {
      std::fprintf(stderr,
                   "afhub demo: the simulation showed no body within %lld s; see its messages "
                   "above\n",
                   static_cast<long long>(kSceneTimeout.count()));
      kill(physics, SIGTERM);
      waitpid(physics, nullptr, 0);
      stop_viewer(viewer);
      return 1;
    }
    int status = 0;
    if (waitpid(physics, &status, WNOHANG) == physics) {
      std::fprintf(stderr, "afhub demo: the simulation exited unexpectedly\n");
      stop_viewer(viewer);
      return 1;
    }
    const BodyList& list = catalog.latest();
    if (!live && list.body_count > 0) live = now;
    if (movers.empty() && list.body_count > 0) {
      if (options.model.empty()) {
        for (const BodyMotion& motion : example_scene_motions())
          movers.emplace_back(std::make_unique<BodyClient>(motion.body), motion.joints);
      } else {
        // The root body (the first in the catalog with joints) carries every joint.
        for (std::uint32_t i = 0; i < list.body_count && movers.empty(); ++i)
          if (list.bodies[i].joint_count > 0)
            movers.emplace_back(
                std::make_unique<BodyClient>(std::string(name_of(list.bodies[i].channel))),
                wave_every_joint(list.bodies[i].joint_count));
      }
    }
    for (auto& [body, motion] : movers) move_joints(*body, motion, t);
    // Drawn at the refresh rate, and at once when bodies come or go.
    if (now >= next_draw || list.body_count != drawn_bodies) {
      drawn_bodies = list.body_count;
      draw(catalog, clients, tty, viewer.url);
      next_draw = now + refresh;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  stop_viewer(viewer);
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
      "Run the demo: a hub, the example scene (a 7-DOF arm, a remote-centre-of-motion arm "
      "and a gripper) simulated in Bullet at 1 kHz with their joints moving, a live table "
      "of their bodies, and `afhub view` serving the 3D scene to a browser (its URL is "
      "printed).");
  demo->add_option("--model", options->model,
                   "ADF file to simulate instead, its root body's joints waving (default: the "
                   "example scene, examples/models/launch.yaml)");
  demo->add_option("--seconds", options->seconds,
                   "Stop after this many seconds of the scene live, counted from its "
                   "bodies' first appearance (default: until Ctrl-C)");
  demo->add_flag("!--no-view", options->view, "Do not start the browser viewer");
  demo->add_flag("!--no-browser", options->open_browser,
                 "Do not open the viewer's URL in your browser (it is opened with xdg-open "
                 "when a display is set)");
  demo->add_option("--view-port", options->view_port,
                   "The viewer's TCP port (0: any free one; the URL printed says which)")
      ->capture_default_str();
  demo->callback([&selected, options] { selected = [options] { return run_demo(*options); }; });
}

}  // namespace afhub::cli
