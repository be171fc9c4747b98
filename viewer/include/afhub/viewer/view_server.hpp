// The viewer's web server, on civetweb (an embedded C HTTP and WebSocket server):
//   /              the page (/?camera=NAME: that world camera's viewport), from viewer/web/,
//                  embedded at build time (web_files.hpp)
//   /viewer.js, /viewer.css   its script and style, the same way
//   /scene.json    the scene: bodies, meshes by index, lights, cameras
//   /joints.json   each live body's joint names (for the sliders)
//   /options.json  {"commands": true|false}
//   /paired.json   input devices' paired cameras, {"CAMERA": ["DEVICE", ...]} (--input-devices)
//   /three/FILE    three.js and the few example files the page uses, from Debian's
//                  libjs-three (/usr/share/javascript/three), by a fixed list
//   /mesh/N        the mesh file scene body N lists, when it is a regular file of a
//                  mesh format within a model folder the scene lists (mesh_file.hpp)
//   /ws            a WebSocket: binary pose frames (pose_feed.hpp), pushed by broadcast();
//                  each page has its own sender (frame_sender.hpp), and a page that stops
//                  reading (no answer to pings for 5 s, or a write stuck for 5 s) is
//                  disconnected, as is one that sends a frame longer than 16 KiB
//                  (src/page_socket.hpp)
//   /command       POST: a joint command; refused (403) unless the server allows commands
//                  and the request carries the command token (X-Afhub-Token)
//   /world         POST action=pause|resume|step|reset; refused (403) the same way
// Every request, the WebSocket's included, must name the viewer in its Host header
// and come from no other site's page (its Origin): page_access.hpp.
// Anything else is 404; nothing else is read from the disk. One address may hold
// kConnectionsPerAddress connections; more are closed at once. At most kMaxPages
// WebSockets are open at once; one more is refused (503, saying so). A request's headers
// must come within 5 s.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
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
  // With allow_commands: what a command's X-Afhub-Token header must hold (random_token()
  // in page_access.hpp; the page reads it from its URL, /?token=...).
  std::string token;
  // With allow_commands: runs a command's query string ("body=3&joint=1&value=0.5"),
  // returning "" when done or what is wrong.
  std::function<std::string(const std::string&)> run_command;
  // With allow_commands: runs a world command's query string ("action=pause"), the same way.
  std::function<std::string(const std::string&)> run_world;
  std::string paired_cameras_json = "{}";  // what /paired.json serves
};

// Connections one address may hold open (a browser opens up to 6 at once to a server,
// plus a WebSocket per page), and civetweb's worker threads (one per connection).
inline constexpr int kConnectionsPerAddress = 16;
inline constexpr int kWorkerThreads = 64;
// Pages open at once, from every address together: each holds a worker thread for as
// long as it is open, so half the threads always remain for plain requests (any of the
// 127.x addresses reaches a loopback viewer, so the cap per address alone would not).
inline constexpr int kMaxPages = kWorkerThreads / 2;

class ViewServer {
 public:
  // Starts listening; throws afhub::Error when it cannot (the port in use, say).
  explicit ViewServer(ServerOptions options);
  ~ViewServer();
  ViewServer(const ViewServer&) = delete;
  ViewServer& operator=(const ViewServer&) = delete;

  int port() const { return port_.load(); }
  void set_scene(std::shared_ptr<const ViewScene> scene);
  void set_joints(const std::string& json);
  // Hands one binary frame to every connected page's sender; never waits for a
  // page. Returns how many pages take it.
  int broadcast(const std::vector<std::uint8_t>& frame);
  int connections();

  // civetweb's callbacks (C functions reach the server through their user data).
  int handle_request(mg_connection* connection);
  // /ws: the handshake, then the page's frames until it leaves (page_socket.hpp);
  // returns the status for civetweb's log.
  int serve_page_socket(mg_connection* connection);
  // Answers 403 and returns true when the request's Host or Origin is not the viewer's.
  bool refuse_other_origin(mg_connection* connection);
  // A connection is taken by a thread: an address's connections over its limit, the
  // newest, are closed.
  void admit();

 private:
  std::shared_ptr<const ViewScene> scene();
  // A page's sender (it throws when no thread can be started), and its registration,
  // after the handshake: frames are offered to it from then on.
  std::unique_ptr<FrameSender> make_sender(mg_connection* connection);
  void add_socket(mg_connection* connection, std::unique_ptr<FrameSender> sender);
  void remove_socket(const mg_connection* connection);
  bool page_dropped(const mg_connection* connection);

  ServerOptions options_;
  mg_context* context_ = nullptr;
  std::atomic<int> port_{0};
  std::atomic<bool> stopping_{false};
  std::atomic<int> open_pages_{0};  // WebSockets being served, at most kMaxPages
  std::mutex mutex_;                // guards scene_, joints_json_, senders_ and refused_
  std::shared_ptr<const ViewScene> scene_;
  std::string joints_json_ = "{}";
  std::map<const mg_connection*, std::unique_ptr<FrameSender>> senders_;
  std::set<std::string> refused_;  // addresses told of their limit
};

}  // namespace afhub::viewer
