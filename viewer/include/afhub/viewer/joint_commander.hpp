// The page's joint sliders (`afhub view --allow-commands`): a request
// "body=CHANNEL&joint=INDEX&value=V" sends one position command to the body, the
// named joint to V and its other joints held where they are. A command is sent
// once; the page repeats it while the slider moves, and the physics' watchdog
// releases the joints when it stops. Called from the server's threads.
//
// Each body commanded takes a BodyClient (an iceoryx publisher and subscriber port,
// of the hub's 512 publishers): only bodies the catalog lists are taken, at most
// `max_clients` at once, the least recently used closed for a new one.
#pragma once

#include <cstddef>
#include <list>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "afhub/hub/bodies.hpp"

namespace afhub::viewer {

inline constexpr std::size_t kMaxBodyClients = 32;

class JointCommander {
 public:
  explicit JointCommander(std::size_t max_clients = kMaxBodyClients) : max_clients_(max_clients) {}

  // The bodies that may be commanded: the catalog's (the viewer's loop sets them when
  // the catalog changes).
  void set_bodies(const std::vector<std::string>& bodies);
  // Returns "" when the command was sent, else what is wrong with the request.
  std::string run(const std::string& query);
  // BodyClients open now (for the tests).
  std::size_t open_clients();

 private:
  // A body's client; its own mutex, since iceoryx's ports are not for two threads at once.
  struct Client {
    explicit Client(const std::string& body) : client(body) {}
    std::mutex mutex;
    BodyClient client;
    bool pools_checked = false;  // the hub's pools, before the first command (guarded)
  };
  // The body's client, opened when it has none (closing the least recently used one
  // over the cap), or nullptr when the catalog does not list the body.
  std::shared_ptr<Client> client_for(const std::string& body);

  const std::size_t max_clients_;
  std::mutex mutex_;  // guards bodies_ and clients_; held for no wait
  std::set<std::string> bodies_;
  // Most recently used first. A client closed here lives on while a request uses it.
  std::list<std::pair<std::string, std::shared_ptr<Client>>> clients_;
};

}  // namespace afhub::viewer
