// `afhub view`: the live scene in a browser (see viewer/).
#include <time.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <thread>

#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/json_writer.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/teleop/input_devices_reader.hpp"
#include "afhub/viewer/joint_commander.hpp"
#include "afhub/viewer/page_access.hpp"
#include "afhub/viewer/pose_feed.hpp"
#include "afhub/viewer/view_server.hpp"
#include "afhub/viewer/world_commander.hpp"
#include "commands.hpp"
#include "connection_options.hpp"

namespace afhub::cli {
namespace {

struct ViewOptions {
  int port = 8080;
  std::string bind = "127.0.0.1";
  bool allow_commands = false;
  bool insecure_remote_commands = false;  // --allow-commands on an address others reach
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

// After a hub loss the viewer re-executes (hub_loss.hpp) and listens again on the port
// it had, where its pages reconnect: a port picked with --port 0 is passed on here.
constexpr const char* kKeptPortVariable = "AFHUB_VIEW_PORT";
// Its command token likewise, so that the pages' URLs stay good.
constexpr const char* kKeptTokenVariable = "AFHUB_VIEW_TOKEN";

// The command token: the one this viewer had before a re-exec, or a new one.
std::string command_token() {
  const char* kept = std::getenv(kKeptTokenVariable);
  std::string token = kept ? kept : viewer::random_token();
  setenv(kKeptTokenVariable, token.c_str(), 1);
  return token;
}

// Sends the hub-lost frame at display rate until `attached`: the pages say so while
// connect_to_hub() waits for a hub to come back.
void send_hub_lost_frames(viewer::ViewServer& server, std::int64_t period_ns,
                          const std::atomic<bool>& attached) {
  const std::vector<std::uint8_t> frame = viewer::hub_lost_frame();
  while (!attached) {
    server.broadcast(frame);
    sleep_until_ns(monotonic_ns() + period_ns);
  }
}

int run_view(const ViewOptions& options) {
  if (options.port < 0 || options.port > 65535) throw Error("--port takes 0 to 65535");
  viewer::require_ip_address(options.bind);
  if (!(options.rate_hz >= 1.0 && options.rate_hz <= 240.0))
    throw Error("--rate takes 1 to 240 frames per second");
  // Any machine that reaches the address could drive the robot (the token travels in
  // clear text over HTTP): only on loopback, unless the user says otherwise.
  const bool remote_commands = options.allow_commands && !viewer::is_loopback(options.bind);
  if (remote_commands && !options.insecure_remote_commands)
    throw Error("--allow-commands with --bind " + options.bind +
                " would let other machines drive the robot over plain HTTP; bind to "
                "127.0.0.1 (reach it from elsewhere through an SSH tunnel), or, on a network "
                "only trusted hosts reach, add --insecure-remote-commands");
  if (remote_commands)
    std::fprintf(stderr,
                 "afhub view: INSECURE: commands are allowed from other machines (--bind %s "
                 "--insecure-remote-commands); the token travels unencrypted\n",
                 options.bind.c_str());
  viewer::ServerOptions server_options;
  if (!options.input_devices.empty())
    server_options.paired_cameras_json = paired_cameras_json(options.input_devices);
  install_stop_signal_handlers();
  server_options.bind = options.bind;
  server_options.port = options.port;
  if (const char* kept = std::getenv(kKeptPortVariable)) {
    server_options.port = std::atoi(kept);
    unsetenv(kKeptPortVariable);
  }
  server_options.allow_commands = options.allow_commands;
  if (options.allow_commands) server_options.token = command_token();
  // The commanders need the hub: until it is attached (and once it is lost) a command
  // is refused.
  std::atomic<bool> attached{false};
  std::unique_ptr<viewer::JointCommander> commander;
  std::unique_ptr<viewer::WorldCommander> world;
  const auto no_hub = [&attached] { return !attached || hub_lost(); };
  const std::string no_hub_text = "the viewer has no hub; it re-attaches when one comes back";
  if (options.allow_commands) {
    server_options.run_command = [&](const std::string& query) {
      return no_hub() ? no_hub_text : commander->run(query);
    };
    server_options.run_world = [&](const std::string& query) {
      return no_hub() ? no_hub_text : world->run(query);
    };
  }
  // Serving before the hub is attached: after a re-exec, pages reconnect at once and
  // are told that the hub is lost.
  viewer::ViewServer server(server_options);
  setenv(kKeptPortVariable, std::to_string(server.port()).c_str(), 1);
  survive_hub_loss("afhub view");
  const auto period_ns = static_cast<std::int64_t>(1e9 / options.rate_hz);
  {
    std::thread lost_frames;
    if (reattach_count() > 0)
      lost_frames =
          std::thread(send_hub_lost_frames, std::ref(server), period_ns, std::cref(attached));
    try {
      connect_to_hub("view", HubPolicy::kRequire);
    } catch (...) {
      attached = true;  // ends the thread
      if (lost_frames.joinable()) lost_frames.join();
      throw;
    }
    commander = std::make_unique<viewer::JointCommander>();
    world = std::make_unique<viewer::WorldCommander>(world_instance(options.name_space));
    attached = true;
    if (lost_frames.joinable()) lost_frames.join();
  }
  viewer::PoseFeed feed(world_instance(options.name_space));
  // With commands, the URL carries the token: only a page opened at it may command.
  const std::string query = options.allow_commands ? "?token=" + server_options.token : "";
  std::printf("afhub view: http://%s:%d/%s (%s; Ctrl-C stops)\n",
              viewer::url_host(options.bind).c_str(), server.port(), query.c_str(),
              !options.allow_commands ? "read-only: no commands"
              : remote_commands       ? "commands allowed, INSECURE: from other machines too"
                                      : "commands allowed from this URL only");
  std::fflush(stdout);
  // Display rate, by absolute deadlines: the viewer reads the hub this often, never
  // at the physics' rate.
  std::int64_t deadline = monotonic_ns();
  std::vector<std::uint8_t> frame;
  const std::vector<std::uint8_t> lost = viewer::hub_lost_frame();
  while (!stop_requested()) {
    if (hub_lost()) {
      // Until the re-exec: the last frame read is not sent again as if live.
      server.broadcast(lost);
    } else {
      if (auto scene = feed.update(frame)) server.set_scene(std::move(scene));
      if (feed.joints_changed()) {
        server.set_joints(feed.joints_json());
        commander->set_bodies(feed.catalog_channels());
      }
      server.broadcast(frame);
    }
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
                 "world (off: the page is read-only); only a page opened at the URL printed, "
                 "which carries a token, may.");
  view->add_flag("--insecure-remote-commands", options->insecure_remote_commands,
                 "With --allow-commands and a --bind address other machines reach: allow it "
                 "(refused otherwise; the token travels unencrypted).")
      ->needs("--allow-commands");
  view->add_option("--rate", options->rate_hz, "Pose frames per second.")->capture_default_str();
  add_world_namespace_option(view, options->name_space);
  view->add_option("--input-devices", options->input_devices,
                   "AMBF input_devices.yaml: mark the cameras its devices pair (\"pair "
                   "cameras\") in the page's viewport list.");
  view->callback([&selected, options] { selected = [options] { return run_view(*options); }; });
}

}  // namespace afhub::cli
