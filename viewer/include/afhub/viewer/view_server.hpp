// The viewer's web server, on civetweb (an embedded C HTTP and WebSocket server):
//   /              the page (/?camera=NAME: that world camera's viewport)
//   /viewer.js     its script
//   /scene.json    the scene: bodies, meshes by index, lights, cameras
//   /joints.json   each live body's joint names (for the sliders)
//   /options.json  {"commands": true|false}
//   /paired.json   input devices' paired cameras, {"CAMERA": ["DEVICE", ...]} (--input-devices)
//   /three/FILE    three.js and the few example files the page uses, from Debian's
//                  libjs-three (/usr/share/javascript/three), by a fixed list
//   /mesh/N        the mesh file scene body N lists, and no other file
//   /ws            a WebSocket: binary pose frames (pose_feed.hpp), pushed by broadcast();
//                  each page has its own sender (frame_sender.hpp), and a page that stops
//                  reading (no answer to pings for a few seconds) is disconnected
//   /command       POST: a joint command; refused (403) unless the server allows commands
//   /world         POST action=pause|resume|step|reset; refused (403) the same way
// Anything else is 404; nothing else is read from the disk.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "afhub/viewer/frame_sender.hpp"
#include "afhub/viewer/view_scene.hpp"

struct mg_context;
struct mg_connection;

namespace afhub::viewer {

struct ServerOptions {
  std::string bind = "127.0.0.1";
  int port = 8080;  // 0: any free port (see ViewServer::port)
  bool allow_commands = false;
  // With allow_commands: runs a command's query string ("body=3&joint=1&value=0.5"),
  // returning "" when done or what is wrong.
  std::function<std::string(const std::string&)> run_command;
  // With allow_commands: runs a world command's query string ("action=pause"), the same way.
  std::function<std::string(const std::string&)> run_world;
  std::string paired_cameras_json = "{}";  // what /paired.json serves
};

class ViewServer {
 public:
  // Starts listening; throws afhub::Error when it cannot (the port in use, say).
  explicit ViewServer(ServerOptions options);
  ~ViewServer();
  ViewServer(const ViewServer&) = delete;
  ViewServer& operator=(const ViewServer&) = delete;

  int port() const { return port_; }
  void set_scene(std::shared_ptr<const ViewScene> scene);
  void set_joints(const std::string& json);
  // Hands one binary frame to every connected page's sender; never waits for a
  // page. Returns how many pages take it.
  int broadcast(const std::vector<std::uint8_t>& frame);
  int connections();

  // civetweb's callbacks (C functions reach the server through their user data).
  int handle_request(mg_connection* connection);
  void add_socket(mg_connection* connection);
  void remove_socket(const mg_connection* connection);

 private:
  std::shared_ptr<const ViewScene> scene();
  ServerOptions options_;
  mg_context* context_ = nullptr;
  int port_ = 0;
  std::mutex mutex_;  // guards scene_, joints_json_ and senders_
  std::shared_ptr<const ViewScene> scene_;
  std::string joints_json_ = "{}";
  std::map<const mg_connection*, std::unique_ptr<FrameSender>> senders_;
};

// The page and its script (page.cpp).
const std::string& page_html();
const std::string& page_script();

}  // namespace afhub::viewer
