// The viewer's web server (see view_server.hpp).
#include "afhub/viewer/view_server.hpp"

#include <civetweb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <strings.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <map>
#include <string_view>

#include "afhub/shm_layout/error.hpp"
#include "afhub/viewer/page_access.hpp"
#include "connection_socket.hpp"
#include "mesh_file.hpp"
#include "page_socket.hpp"
#include "web_files.hpp"
#include "websocket_frames.hpp"

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

// The content type of an embedded page file, by its extension.
const char* web_type(std::string_view name) {
  if (name.ends_with(".html")) return "text/html; charset=utf-8";
  if (name.ends_with(".css")) return "text/css";
  return "text/javascript";
}

void send_text(mg_connection* connection, int status, const char* type, std::string_view body) {
  mg_printf(connection,
            "HTTP/1.1 %d %s\r\nContent-Type: %s\r\nContent-Length: %zu\r\n"
            "Cache-Control: no-store\r\nConnection: close\r\n\r\n",
            status, status == 200 ? "OK" : "Error", type, body.size());
  mg_write(connection, body.data(), body.size());
}

// The opened mesh, whole (a mesh that ends early is cut short: the page sees a broken mesh).
void send_mesh(mg_connection* connection, const MeshFile& mesh) {
  mg_printf(connection,
            "HTTP/1.1 200 OK\r\nContent-Type: application/octet-stream\r\nContent-Length: "
            "%zu\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n",
            mesh.size());
  char buffer[8192];  // civetweb's threads have small stacks (100 kB in Debian's build)
  for (std::size_t left = mesh.size(); left > 0;) {
    const ssize_t n = read(mesh.fd(), buffer, std::min(sizeof buffer, left));
    if (n <= 0 || mg_write(connection, buffer, static_cast<std::size_t>(n)) != n) return;
    left -= static_cast<std::size_t>(n);
  }
}

int on_request(mg_connection* connection, void* server) {
  return static_cast<ViewServer*>(server)->handle_request(connection);
}

ViewServer* server_of(const mg_connection* connection) {
  return static_cast<ViewServer*>(mg_get_user_data(mg_get_context(connection)));
}

// civetweb sends a WebSocket upgrade only to its own WebSocket handlers, never to a
// request handler: /ws is taken here, before civetweb looks at it.
int on_begin_request(mg_connection* connection) {
  const mg_request_info* request = mg_get_request_info(connection);
  if (!request->local_uri_raw || std::strcmp(request->local_uri_raw, "/ws") != 0) return 0;
  ViewServer* server = server_of(connection);
  return server->refuse_other_origin(connection) ? 403 : server->serve_page_socket(connection);
}

int on_connection(const mg_connection* connection, void**) {
  server_of(connection)->admit();
  return 0;
}

// One unmasked frame to a page, whole, while no other thread writes to it.
bool write_frame(mg_connection* connection, Opcode opcode, std::string_view payload) {
  std::uint8_t header[10];
  const std::size_t header_size = write_frame_header(header, opcode, payload.size());
  mg_lock_connection(connection);
  // mg_write returns what it wrote: less when a write made no progress for 5 s.
  const bool whole = mg_write(connection, header, header_size) == static_cast<int>(header_size) &&
                     (payload.empty() || mg_write(connection, payload.data(), payload.size()) ==
                                             static_cast<int>(payload.size()));
  mg_unlock_connection(connection);
  return whole;
}

}  // namespace

ViewServer::ViewServer(ServerOptions options)
    : options_(std::move(options)), scene_(std::make_shared<ViewScene>(no_scene())) {
  if (options_.allow_commands && options_.token.empty())
    throw Error("the viewer allows commands only with a command token");
  mg_init_library(0);
  constexpr unsigned kIpv6Feature = 8;  // civetweb's feature bit
  if (options_.bind.find(':') != std::string::npos && !mg_check_feature(kIpv6Feature))
    throw Error("cannot listen on " + options_.bind +
                ": the civetweb afhub is built with listens on IPv4 only (Debian's is built "
                "without IPv6); bind to 127.0.0.1, or 0.0.0.0 for every interface");
  const std::string listen = url_host(options_.bind) + ":" + std::to_string(options_.port);
  // No document root: civetweb serves no file by itself, only what the handler sends.
  // Each connection has a worker thread of its own (a page's WebSocket keeps its
  // thread), so that an address may hold only kConnectionsPerAddress of them, and a
  // request's headers must have come within 5 s: idle and slow connections from one
  // address never keep the others' requests waiting. A write that makes no progress
  // for 5 s fails (a page that stopped reading is dropped).
  const std::string threads = std::to_string(kWorkerThreads);
  const char* settings[] = {"listening_ports",
                            listen.c_str(),
                            "num_threads",
                            threads.c_str(),
                            "enable_directory_listing",
                            "no",
                            "enable_keep_alive",
                            "no",
                            "request_timeout_ms",
                            "5000",
                            nullptr};
  mg_callbacks callbacks{};
  callbacks.begin_request = on_begin_request;
  callbacks.init_connection = on_connection;
  context_ = mg_start(&callbacks, this, settings);
  if (!context_)
    throw Error("cannot listen on " + listen +
                ": the port is in use or the address is not this machine's; pick another "
                "with --port or --bind");
  mg_set_request_handler(context_, "/", on_request, this);
  mg_server_port ports[4]{};
  const int count = mg_get_server_ports(context_, 4, ports);
  port_ = count > 0 ? ports[0].port : options_.port;
}

ViewServer::~ViewServer() {
  stopping_ = true;  // pages' WebSocket readers end, so that mg_stop's wait does
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

std::unique_ptr<FrameSender> ViewServer::make_sender(mg_connection* connection) {
  return std::make_unique<FrameSender>([connection](const std::uint8_t* data, std::size_t size) {
    // A write that timed out part-way broke the stream.
    if (write_frame(connection, Opcode::kBinary,
                    std::string_view(reinterpret_cast<const char*>(data), size)))
      return true;
    std::fprintf(stderr,
                 "afhub view: dropped a page: a frame could not be sent (the page closed its "
                 "connection, or stopped reading for 5 s)\n");
    return false;
  });
}

void ViewServer::add_socket(mg_connection* connection, std::unique_ptr<FrameSender> sender) {
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

bool ViewServer::page_dropped(const mg_connection* connection) {
  std::lock_guard lock(mutex_);
  const auto found = senders_.find(connection);
  return found == senders_.end() || found->second->dropped();
}

void ViewServer::admit() {
  // civetweb says nothing of a connection before its request has come (its request
  // info is empty until then), so the connections are counted from their sockets:
  // those accepted and not yet closed, queued for a thread or served.
  std::vector<ServerSocket> sockets = server_sockets(port_);
  std::sort(sockets.begin(), sockets.end(), [](const ServerSocket& a, const ServerSocket& b) {
    return a.peer != b.peer ? a.peer < b.peer : a.inode < b.inode;
  });
  // Per address, its oldest kConnectionsPerAddress stay; the newer are closed.
  for (std::size_t first = 0, next = 0; first < sockets.size(); first = next) {
    next = first;
    while (next < sockets.size() && sockets[next].peer == sockets[first].peer) ++next;
    if (next - first <= static_cast<std::size_t>(kConnectionsPerAddress)) continue;
    for (std::size_t i = first + kConnectionsPerAddress; i < next; ++i) shut_down(sockets[i]);
    std::lock_guard lock(mutex_);
    if (refused_.insert(sockets[first].peer).second)
      std::fprintf(stderr,
                   "afhub view: %s opened more than %d connections, the most one address may "
                   "have open; closing the newer ones (said once per address)\n",
                   sockets[first].peer.c_str(), kConnectionsPerAddress);
  }
}

int ViewServer::serve_page_socket(mg_connection* connection) {
  const char* upgrade = mg_get_header(connection, "Upgrade");
  const char* key = mg_get_header(connection, "Sec-WebSocket-Key");
  const char* version = mg_get_header(connection, "Sec-WebSocket-Version");
  if (!upgrade || strcasecmp(upgrade, "websocket") != 0 || !key || !version ||
      std::strcmp(version, "13") != 0) {
    send_text(connection, 400, "text/plain",
              "/ws is a WebSocket (version 13): the page opens it\n");
    return 400;
  }
  // A place among the pages, taken before the handshake and given back when the page leaves.
  if (open_pages_.fetch_add(1) >= kMaxPages) {
    --open_pages_;
    send_text(connection, 503, "text/plain",
              "the viewer has " + std::to_string(kMaxPages) +
                  " pages open, the most it serves at once: close one, then reload\n");
    std::fprintf(stderr, "afhub view: refused a page from %s: %d pages are open already\n",
                 mg_get_request_info(connection)->remote_addr, kMaxPages);
    return 503;
  }
  struct GiveBack {
    std::atomic<int>& pages;
    ~GiveBack() { --pages; }
  } give_back{open_pages_};
  const int fd = connection_socket(connection, port_);
  if (fd < 0) {
    send_text(connection, 500, "text/plain", "the viewer lost this connection's socket\n");
    return 500;
  }
  // The page's sender thread, started before the handshake: when the machine has no
  // thread to give (out of pids or memory, under load), the page is refused and retries.
  // The exception would otherwise cross civetweb's C frames and end the viewer.
  std::unique_ptr<FrameSender> sender;
  try {
    sender = make_sender(connection);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "afhub view: refused a page: no thread for its frames (%s)\n",
                 error.what());
    send_text(connection, 503, "text/plain",
              "the viewer could not start a thread for this page; try again\n");
    return 503;
  }
  // A frame goes out as two writes (its header, its payload): sent at once, not held
  // back for the first one's acknowledgement.
  const int on = 1;
  setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &on, sizeof on);
  mg_printf(connection,
            "HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\nConnection: "
            "Upgrade\r\nSec-WebSocket-Accept: %s\r\n\r\n",
            websocket_accept(key).c_str());
  add_socket(connection, std::move(sender));
  const PageEnd end = read_page_frames(
      fd, [this, connection] { return !stopping_ && !page_dropped(connection); },
      [connection](Opcode opcode, std::string_view payload) {
        return write_frame(connection, opcode, payload);
      });
  remove_socket(connection);
  if (end.refused) {
    std::fprintf(stderr, "afhub view: closed a WebSocket from %s: %s\n",
                 mg_get_request_info(connection)->remote_addr, end.why.c_str());
    // What the page still sends is not read: civetweb's close then ends at once.
    shutdown(fd, SHUT_RDWR);
  }
  return 101;
}

bool ViewServer::refuse_other_origin(mg_connection* connection) {
  const std::string problem = origin_problem(
      options_.bind, port_, mg_get_header(connection, "Host"), mg_get_header(connection, "Origin"));
  if (problem.empty()) return false;
  send_text(connection, 403, "text/plain", problem + "\n");
  return true;
}

int ViewServer::handle_request(mg_connection* connection) {
  if (refuse_other_origin(connection)) return 1;
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
    const std::string wrong_token =
        token_problem(options_.token, mg_get_header(connection, "X-Afhub-Token"));
    if (!wrong_token.empty()) {
      send_text(connection, 403, "text/plain", wrong_token + "\n");
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
  const std::string_view page_name = uri == "/"             ? "index.html"
                                     : uri.starts_with('/') ? uri.substr(1)
                                                            : "";
  if (const std::optional<std::string_view> page = web_file(page_name)) {
    send_text(connection, 200, web_type(page_name), *page);
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
    const MeshFile mesh(*scene(), uri.substr(6));
    if (!mesh.problem().empty())
      send_text(connection, mesh.status(), "text/plain", mesh.problem() + "\n");
    else
      send_mesh(connection, mesh);
  } else {
    send_text(connection, 404, "text/plain", "not found\n");
  }
  return 1;
}

}  // namespace afhub::viewer
