// Claiming bodies through the hub (see body_claims.hpp).
#include "afhub/hub/body_claims.hpp"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <fstream>
#include <map>
#include <thread>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/channel.hpp"
#include "afhub/hub/hub_health.hpp"
#include "afhub/hub/hub_loss.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/world.hpp"
#include "hub_loss_handling.hpp"
#include "hub_loss_state.hpp"

namespace afhub {

namespace {

// Process `pid`'s state letter in /proc/PID/stat ("pid (name) S ..."), or 0 when it
// cannot be read.
char process_state(std::uint32_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  std::getline(stat, line);
  const std::size_t name_end = line.rfind(')');
  return name_end == std::string::npos || name_end + 2 >= line.size() ? 0 : line[name_end + 2];
}

}  // namespace

bool process_exists(std::uint32_t pid) {
  if (pid == 0 || (kill(static_cast<pid_t>(pid), 0) != 0 && errno != EPERM)) return false;
  // A zombie (dead, its parent has not reaped it yet) owns nothing: it held a restarted
  // physics off for over a second.
  return process_state(pid) != 'Z';
}

bool process_stopped(std::uint32_t pid) {
  const char state = pid == 0 ? 0 : process_state(pid);
  return state == 'T' || state == 't';
}

namespace {

struct Owner {
  std::string name;
  std::uint32_t pid = 0;
};

// The catalog's bodies and their owners.
std::map<std::string, Owner> catalog_owners(CatalogReader& catalog) {
  std::map<std::string, Owner> owners;
  const BodyList& list = catalog.latest();
  for (std::uint32_t i = 0; i < list.body_count; ++i)
    owners[std::string(name_of(list.bodies[i].channel))] = {
        std::string(name_of(list.bodies[i].owner)), list.bodies[i].owner_pid};
  return owners;
}

std::string taken_message(const std::string& channel, const Owner& owner) {
  const std::string by =
      channel + " is published by " + owner.name + " (pid " + std::to_string(owner.pid) + ")";
  if (channel.starts_with("device/"))
    return by + ": a device has one driver. Stop that one, or give this one another --name";
  return by +
         ": a body has one publisher. Stop that process, or run this copy in another "
         "namespace (--namespace)";
}

}  // namespace

void check_world_free(const std::string& world_instance, const std::string& advice) {
  // A new reader finds a live physics' world state within the hub's discovery interval
  // (0.1 s).
  LatestReader<WorldState> reader(
      {std::string(kService), world_instance, std::string(kStateEvent)});
  const WorldState* state = nullptr;
  for (const std::int64_t give_up = monotonic_ns() + 300'000'000;
       !(state = reader.latest()) && monotonic_ns() < give_up;)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  if (!state) return;
  // Copied before it is judged: another process writes it.
  const WorldState first = *state;
  const std::uint32_t pid = first.header.publisher_pid;
  if (pid == static_cast<std::uint32_t>(getpid()) || !process_exists(pid)) return;
  // Its owner still publishing: a newer state within 0.2 s (a live physics publishes every
  // step, paused too, and every 20 ms while it waits for lockstep clients). The last state
  // of a simulation that just ended stays readable, and its process may live on (a test
  // that ran one in its own process, then started `afhub run`, was refused).
  for (const std::int64_t give_up = monotonic_ns() + 200'000'000;
       (state = reader.latest()) &&
       state->header.publish_stamp_ns == first.header.publish_stamp_ns;) {
    if (monotonic_ns() > give_up) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  if (!state) return;
  const WorldState now = *state;
  throw Error("another simulation (pid " + std::to_string(pid) + ", " +
              std::to_string(now.body_count) + " bodies, at step " +
              std::to_string(now.header.sim_step) + ") runs the world '" + world_instance +
              "': two in one world alternate in its state and both obey its commands. " + advice);
}

std::size_t check_room_for_bodies(const std::vector<std::string>& channels,
                                  std::size_t publishers) {
  CatalogReader catalog;
  catalog.wait(std::chrono::milliseconds(1000));
  std::size_t live_bodies = 0, others = 0;
  const auto owners = catalog_owners(catalog);
  for (const auto& [channel, owner] : owners) {
    if (!process_exists(owner.pid)) continue;  // gone; the hub is removing it
    ++live_bodies;
    if (owner.pid == static_cast<std::uint32_t>(getpid())) continue;
    ++others;
    for (const std::string& mine : channels)
      if (mine == channel) throw Error(taken_message(channel, owner));
  }
  if (live_bodies + channels.size() > kMaxBodies)
    throw Error("the hub lists " + std::to_string(live_bodies) + " bodies and this adds " +
                std::to_string(channels.size()) + "; it holds at most " +
                std::to_string(kMaxBodies));
  // Counted afresh: other processes may have taken ports since this one connected.
  count_ports_from(free_ports(std::chrono::milliseconds(1500)));
  const std::string what = "simulating these " + std::to_string(channels.size()) + " bodies";
  require_publisher_ports(publishers, what);
  require_subscriber_ports(1, what);  // the process's reader of command slots
  return others;
}

void confirm_body_claims(const std::vector<std::string>& channels,
                         std::chrono::milliseconds timeout) {
  // Ctrl-C meanwhile ends the process (exit code 0), as while it registered: it waited
  // the whole timeout, then said the hub was stalled (a hub lost just before, too).
  const StopEndsBlockingCall stoppable;
  CatalogReader catalog;
  catalog.wait(timeout);
  const auto me = static_cast<std::uint32_t>(getpid());
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto owners = catalog_owners(catalog);
    std::vector<std::string> missing;
    for (const std::string& channel : channels) {
      const auto found = owners.find(channel);
      if (found != owners.end() && found->second.pid != me && process_exists(found->second.pid))
        throw Error(taken_message(channel, found->second));
      // Not listed yet, or still as a process that is gone: the hub is catching up.
      if (found == owners.end() || found->second.pid != me) missing.push_back(channel);
    }
    if (missing.empty()) return;
    if (hub_lost()) {
      // A process that outlives its hub is being re-executed: it waits for that.
      if (hub_loss::state().reexecs) hub_loss::wait_for_reexec();
      throw Error(
          "the hub went away before it listed this process's bodies: start this "
          "again once a hub runs");
    }
    if (std::chrono::steady_clock::now() > deadline) {
      const std::string not_listed = "the hub did not list " + std::to_string(missing.size()) +
                                     " of " + std::to_string(channels.size()) +
                                     " bodies (first: " + missing.front() + ")";
      if (owners.size() + missing.size() > kMaxBodies)
        throw Error(not_listed + ": its catalog is full (" + std::to_string(kMaxBodies) +
                    " bodies); `afhub ls` shows who holds them");
      throw Error(not_listed + " within " + std::to_string(timeout.count() / 1000) +
                  " s, though its catalog has room: the hub is overloaded or stalled "
                  "(`afhub status`); start this again once it answers");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

}  // namespace afhub
