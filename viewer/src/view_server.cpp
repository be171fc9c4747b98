// The viewer's web server (see view_server.hpp).
#include "afhub/viewer/view_server.hpp"

#include <civetweb.h>

#include <cstdio>
#include <cstring>
#include <map>
#include <string_view>

#include "afhub/shm_layout/error.hpp"

namespace afhub::viewer {
namespace {

constexpr const char* kThreeDir = "/usr/share/javascript/three/";

// The only three.js files served: URL name -> path under kThreeDir.
const std::map<std::string_view, const char*>& three_files() {
  static const std::map<std::string_view, const char*> files = {
      {"three.min.js", "three.min.js"},
      {"OrbitControls.js", "examples/js/controls/OrbitControls.js"},
      {"STLLoader.js", "examples/js/loaders/STLLoader.js"},
      {"OBJLoader.js", "examples/js/loaders/OBJLoader.js"},
  };
  return files;
}

void send_text(mg_connection* connection, int status, const char* type, const std::string& body) {
  mg_printf(connection,
            "HTTP/1.1 %d %s\r\nContent-Type: %s\r\nContent-Length: %zu\r\n"
            "Cache-Control: no-store\r\nConnection: close\r\n\r\n",
            status, status == 200 ? "OK" : "Error", type, body.size());
  mg_write(connection, body.data(), body.size());
}

int on_request(mg_connection* connection, void* server) {
  return static_cast<ViewServer*>(server)->handle_request(connection);
}

int on_socket_connect(const mg_connection*, void*) {
  return 0;
}  // accept

void on_socket_ready(mg_connection* connection, void* server) {
  static_cast<ViewServer*>(server)->add_socket(connection);
}

int on_socket_data(mg_connection*, int, char*, size_t, void*) {
  return 1;
}  // keep open

void on_socket_close(const mg_connection* connection, void* server) {
  static_cast<ViewServer*>(server)->remove_socket(connection);
}

}  // namespace

ViewServer::ViewServer(ServerOptions options)
    : options_(std::move(options)), scene_(std::make_shared<ViewScene>()) {
  mg_init_library(0);
  const std::string listen = options_.bind + ":" + std::to_string(options_.port);
  // No document root: civetweb serves no file by itself, only what the handler sends.
  // A page is pinged after a second without a message from it and disconnected
  // when it leaves pings unanswered: a page that stopped reading, whose frames
  // would pile up in the kernel's socket buffer. A write makes no progress for at
  // most 5 s (it then fails and the page is dropped).
  const char* settings[] = {"listening_ports",
                            listen.c_str(),
                            "num_threads",
                            "16",
                            "enable_directory_listing",
                            "no",
                            "enable_websocket_ping_pong",
                            "yes",
                            "websocket_timeout_ms",
                            "1000",
                            "request_timeout_ms",
                            "5000",
                            nullptr};
  mg_callbacks callbacks{};
  context_ = mg_start(&callbacks, this, settings);
  if (!context_)
    throw Error("cannot listen on " + listen +
                ": the port is in use or the address is not this machine's; pick another "
                "with --port or --bind");
  mg_set_request_handler(context_, "/", on_request, this);
  mg_set_websocket_handler(context_, "/ws", on_socket_connect, on_socket_ready, on_socket_data,
                           on_socket_close, this);
  mg_server_port ports[4]{};
  const int count = mg_get_server_ports(context_, 4, ports);
  port_ = count > 0 ? ports[0].port : options_.port;
}

ViewServer::~ViewServer() {
  if (context_) mg_stop(context_);
  mg_exit_library();
}

void ViewServer::set_scene(std::shared_ptr<const ViewScene> scene) {
  std::lock_guard lock(mutex_);
  scene_ = std::move(scene);
}

void ViewServer::set_joints(const std::string& json) {
  std::lock_guard lock(mutex_);
  joints_json_ = json;
}

std::shared_ptr<const ViewScene> ViewServer::scene() {
  std::lock_guard lock(mutex_);
  return scene_;
}

int ViewServer::broadcast(const std::vector<std::uint8_t>& frame) {
  std::lock_guard lock(mutex_);
  int taken = 0;
  for (auto& [connection, sender] : senders_)
    if (sender->offer(frame)) ++taken;
  return taken;
}

int ViewServer::connections() {
  std::lock_guard lock(mutex_);
  return static_cast<int>(senders_.size());
}

void ViewServer::add_socket(mg_connection* connection) {
  auto sender =
      std::make_unique<FrameSender>([connection](const std::uint8_t* data, std::size_t size) {
        const int written = mg_websocket_write(connection, MG_WEBSOCKET_OPCODE_BINARY,
                                               reinterpret_cast<const char*>(data), size);
        // A write that timed out part-way returns what it wrote: the stream is broken then.
        if (written >= static_cast<int>(size)) return true;
        std::fprintf(stderr,
                     "afhub view: dropped a page that stopped reading (a frame could not be sent "
                     "in 5 s)\n");
        return false;
      });
  std::lock_guard lock(mutex_);
  senders_[connection] = std::move(sender);
}

void ViewServer::remove_socket(const mg_connection* connection) {
  std::unique_ptr<FrameSender> sender;
  {
    std::lock_guard lock(mutex_);
    const auto found = senders_.find(connection);
    if (found == senders_.end()) return;
    sender = std::move(found->second);
    senders_.erase(found);
  }
  // Waits, without the lock, for a write in progress: civetweb frees the connection
  // once this returns.
  sender.reset();
}

int ViewServer::handle_request(mg_connection* connection) {
  const mg_request_info* request = mg_get_request_info(connection);
  // The URI as sent (decoded, not cleaned): every route below is an exact match.
  const std::string_view uri = request->local_uri_raw ? request->local_uri_raw : "";
  const std::string_view method = request->request_method ? request->request_method : "";
  if (uri == "/command" || uri == "/world") {
    const auto& run = uri == "/command" ? options_.run_command : options_.run_world;
    if (!options_.allow_commands || !run) {
      send_text(connection, 403, "text/plain",
                "commands are off: start `afhub view --allow-commands` to drive joints and "
                "pause, step or reset the world\n");
      return 1;
    }
    if (method != "POST") {
      send_text(connection, 405, "text/plain", "POST a command\n");
      return 1;
    }
    const std::string problem = run(request->query_string ? request->query_string : "");
    send_text(connection, problem.empty() ? 200 : 400, "text/plain",
              problem.empty() ? "ok\n" : problem + "\n");
    return 1;
  }
  if (method != "GET" && method != "HEAD") {
    send_text(connection, 405, "text/plain", "the viewer serves GET requests only\n");
    return 1;
  }
  if (uri == "/" || uri == "/index.html") {
    send_text(connection, 200, "text/html; charset=utf-8", page_html());
  } else if (uri == "/viewer.js") {
    send_text(connection, 200, "text/javascript", page_script());
  } else if (uri == "/scene.json") {
    send_text(connection, 200, "application/json", scene()->json);
  } else if (uri == "/joints.json") {
    std::string joints;
    {
      std::lock_guard lock(mutex_);
      joints = joints_json_;
    }
    send_text(connection, 200, "application/json", joints);
  } else if (uri == "/options.json") {
    send_text(connection, 200, "application/json",
              options_.allow_commands ? R"({"commands":true})" : R"({"commands":false})");
  } else if (uri == "/paired.json") {
    send_text(connection, 200, "application/json", options_.paired_cameras_json);
  } else if (uri.starts_with("/three/")) {
    const auto file = three_files().find(uri.substr(7));
    if (file == three_files().end()) {
      send_text(connection, 404, "text/plain", "not a three.js file the viewer serves\n");
      return 1;
    }
    mg_send_mime_file(connection, (std::string(kThreeDir) + file->second).c_str(),
                      "text/javascript");
  } else if (uri.starts_with("/mesh/")) {
    const std::optional<std::string> path = listed_mesh(*scene(), uri.substr(6));
    if (!path) {
      send_text(connection, 404, "text/plain", "not a mesh the scene lists\n");
      return 1;
    }
    mg_send_mime_file(connection, path->c_str(), "application/octet-stream");
  } else {
    send_text(connection, 404, "text/plain", "not found\n");
  }
  return 1;
}

}  // namespace afhub::viewer
