// `afhub view`: the live scene in a browser (see viewer/).
#include <time.h>

#include <cstdio>
#include <map>
#include <memory>

#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/json_writer.hpp"
#include "afhub/hub/stop_signal.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/teleop/input_devices_reader.hpp"
#include "afhub/viewer/joint_commander.hpp"
#include "afhub/viewer/pose_feed.hpp"
#include "afhub/viewer/view_server.hpp"
#include "afhub/viewer/world_commander.hpp"
#include "commands.hpp"

namespace afhub::cli {
namespace {

struct ViewOptions {
  int port = 8080;
  std::string bind = "127.0.0.1";
  bool allow_commands = false;
  double rate_hz = 60.0;
  std::string name_space;
  std::string input_devices;  // input_devices.yaml: its devices' paired cameras are marked
};

// {"CAMERA": ["DEVICE", ...]}: the cameras the file's devices pair (their "pair
// cameras", world file camera names as teleop reads them).
std::string paired_cameras_json(const std::string& path) {
  const teleop::InputDevicesFile file = teleop::read_input_devices(path);
  std::map<std::string, std::vector<std::string>> paired;
  for (const teleop::InputDeviceSpec& device : file.devices)
    for (const std::string& camera : device.pair_cameras)
      paired[camera].push_back(device.identifier);
  JsonWriter json;
  json.begin_object();
  for (const auto& [camera, devices] : paired) {
    json.key(camera).begin_array();
    for (const std::string& device : devices) json.value(device);
    json.end_array();
  }
  json.end_object();
  return json.str();
}

int run_view(const ViewOptions& options) {
  if (options.port < 0 || options.port > 65535) throw Error("--port takes 0 to 65535");
  if (!(options.rate_hz >= 1.0 && options.rate_hz <= 240.0))
    throw Error("--rate takes 1 to 240 frames per second");
  viewer::ServerOptions server_options;
  if (!options.input_devices.empty())
    server_options.paired_cameras_json = paired_cameras_json(options.input_devices);
  install_stop_signal_handlers();
  connect_to_hub("view", HubPolicy::kRequire);
  viewer::PoseFeed feed(world_instance(options.name_space));
  viewer::JointCommander commander;
  viewer::WorldCommander world(world_instance(options.name_space));
  server_options.bind = options.bind;
  server_options.port = options.port;
  server_options.allow_commands = options.allow_commands;
  if (options.allow_commands) {
    server_options.run_command = [&commander](const std::string& query) {
      return commander.run(query);
    };
    server_options.run_world = [&world](const std::string& query) { return world.run(query); };
  }
  viewer::ViewServer server(server_options);
  std::printf("afhub view: http://%s:%d/ (%s; Ctrl-C stops)\n", options.bind.c_str(), server.port(),
              options.allow_commands ? "commands allowed" : "read-only: no commands");
  std::fflush(stdout);
  // Display rate, by absolute deadlines: the viewer reads the hub this often, never
  // at the physics' rate.
  const auto period_ns = static_cast<std::int64_t>(1e9 / options.rate_hz);
  std::int64_t deadline = monotonic_ns();
  std::vector<std::uint8_t> frame;
  while (!stop_requested()) {
    if (auto scene = feed.update(frame)) server.set_scene(std::move(scene));
    if (feed.joints_changed()) server.set_joints(feed.joints_json());
    server.broadcast(frame);
    deadline += period_ns;
    const std::int64_t now = monotonic_ns();
    if (deadline < now) deadline = now;  // after a stall, go on from now
    const timespec until{static_cast<time_t>(deadline / 1'000'000'000),
                         static_cast<long>(deadline % 1'000'000'000)};
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &until, nullptr);
  }
  return 0;
}

}  // namespace

void register_view(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<ViewOptions>();
  auto* view = app.add_subcommand(
      "view",
      "Serve the live scene to a browser: bodies with their meshes or shapes, lights, a "
      "floor, one viewport per world camera (/?camera=NAME), poses over a WebSocket.");
  view->add_option("--port", options->port, "TCP port (0: any free one, printed).")
      ->capture_default_str();
  view->add_option("--bind", options->bind,
                   "Address to listen on; 0.0.0.0 lets other machines watch.")
      ->capture_default_str();
  view->add_flag("--allow-commands", options->allow_commands,
                 "Let the page send joint position commands and pause, step and reset the "
                 "world (off: the page is read-only).");
  view->add_option("--rate", options->rate_hz, "Pose frames per second.")->capture_default_str();
  view->add_option("--namespace", options->name_space,
                   "The world of an `afhub run --namespace PREFIX`.");
  view->add_option("--input-devices", options->input_devices,
                   "AMBF input_devices.yaml: mark the cameras its devices pair (\"pair "
                   "cameras\") in the page's viewport list.");
  view->callback([&selected, options] { selected = [options] { return run_view(*options); }; });
}

}  // namespace afhub::cli
