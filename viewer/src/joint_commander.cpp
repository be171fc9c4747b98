// The page's joint commands (see joint_commander.hpp).
#include "afhub/viewer/joint_commander.hpp"

#include <civetweb.h>
#include <time.h>

#include <cmath>
#include <cstdlib>

#include "afhub/hub/hub_health.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/yaml/number_text.hpp"

namespace afhub::viewer {
namespace {

// The value of `name` in a query string, or "" when it is missing.
std::string query_value(const std::string& query, const char* name) {
  char value[256];
  const int length = mg_get_var(query.c_str(), query.size(), name, value, sizeof value);
  return length < 0 ? std::string() : std::string(value, static_cast<std::size_t>(length));
}

}  // namespace

void JointCommander::set_bodies(const std::vector<std::string>& bodies) {
  std::set<std::string> listed(bodies.begin(), bodies.end());
  std::list<std::pair<std::string, std::shared_ptr<Client>>> gone;
  {
    std::lock_guard lock(mutex_);
    bodies_.swap(listed);
    // A body that left the catalog gives its ports back.
    for (auto at = clients_.begin(); at != clients_.end();) {
      const auto next = std::next(at);
      if (!bodies_.count(at->first)) gone.splice(gone.end(), clients_, at);
      at = next;
    }
  }
  // Closed here, without the lock.
}

std::size_t JointCommander::open_clients() {
  std::lock_guard lock(mutex_);
  return clients_.size();
}

std::shared_ptr<JointCommander::Client> JointCommander::client_for(const std::string& body) {
  const auto find = [this, &body]() -> std::shared_ptr<Client> {
    for (auto at = clients_.begin(); at != clients_.end(); ++at)
      if (at->first == body) {
        clients_.splice(clients_.begin(), clients_, at);
        return clients_.front().second;
      }
    return nullptr;
  };
  {
    std::lock_guard lock(mutex_);
    if (!bodies_.count(body)) return nullptr;
    if (std::shared_ptr<Client> open = find()) return open;
  }
  // Opened without the lock (it asks the hub for two ports).
  auto made = std::make_shared<Client>(body);
  std::shared_ptr<Client> evicted;  // closed once the lock is released
  std::lock_guard lock(mutex_);
  if (std::shared_ptr<Client> open = find()) return open;  // another request opened it
  if (clients_.size() >= max_clients_) {
    evicted = std::move(clients_.back().second);
    clients_.pop_back();
  }
  clients_.emplace_front(body, made);
  return made;
}

std::string JointCommander::run(const std::string& query) {
  const std::string body = query_value(query, "body");
  const std::string joint_text = query_value(query, "joint");
  const std::string value_text = query_value(query, "value");
  if (body.empty() || joint_text.empty() || value_text.empty())
    return "a command takes body=CHANNEL&joint=INDEX&value=V";
  if (!channel_name_problem(body).empty()) return "body: not a channel name: " + body;
  char* end = nullptr;
  const unsigned long joint = std::strtoul(joint_text.c_str(), &end, 10);
  if (*end != '\0' || joint_text[0] == '-') return "joint: a joint index, got " + joint_text;
  const std::optional<double> value = yaml::parse_finite(value_text);
  if (!value) return "value: a finite number, got " + value_text;

  std::shared_ptr<Client> client;
  try {
    client = client_for(body);
  } catch (const std::exception& error) {  // no ports left: said, not thrown into civetweb
    return "cannot command " + body + ": " + error.what();
  }
  if (!client) return "body: " + body + " is not a body the catalog lists (afhub ls)";
  std::unique_lock lock(client->mutex);
  const BodyState* state = client->client.latest_state();
  for (int tries = 0; !state && tries < 50; ++tries) {
    // A new reader waits for a state; other requests, this body's too, go on meanwhile.
    lock.unlock();
    const timespec pause{0, 2'000'000};
    nanosleep(&pause, nullptr);
    lock.lock();
    state = client->client.latest_state();
  }
  if (!state) return "no state from " + body + ": is it a live body (afhub ls)?";
  if (joint >= state->joint_count)
    return "joint: " + body + " has " + std::to_string(state->joint_count) + " joints, got index " +
           joint_text;
  if (!client->pools_checked) {
    // Before the first loan, as every publisher: a page must not starve a running physics.
    try {
      require_chunks({written_as_slot(body_command_bytes(state->joint_count))},
                     "the viewer's commands to " + body);
    } catch (const std::exception& error) {
      return error.what();
    }
    client->pools_checked = true;
  }
  BodyCommand* command = client->client.loan_command(state->joint_count);
  if (!command) return "no shared memory for a command";
  for (std::uint32_t j = 0; j < state->joint_count; ++j)
    command->joints[j] = {
        j == joint ? *value : state->joints[j].position, JointCommandType::kPosition, {}};
  command->header.sim_step = state->header.sim_step;
  client->client.publish_command(command);
  return "";
}

}  // namespace afhub::viewer
