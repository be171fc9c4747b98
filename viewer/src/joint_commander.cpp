// The page's joint commands (see joint_commander.hpp).
#include "afhub/viewer/joint_commander.hpp"

#include <civetweb.h>

#include <cmath>
#include <cstdlib>

#include "afhub/shm_layout/channel_names.hpp"

namespace afhub::viewer {
namespace {

// The value of `name` in a query string, or "" when it is missing.
std::string query_value(const std::string& query, const char* name) {
  char value[256];
  const int length = mg_get_var(query.c_str(), query.size(), name, value, sizeof value);
  return length < 0 ? std::string() : std::string(value, static_cast<std::size_t>(length));
}

}  // namespace

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
  const double value = std::strtod(value_text.c_str(), &end);
  if (*end != '\0' || !std::isfinite(value)) return "value: a finite number, got " + value_text;

  std::lock_guard lock(mutex_);
  std::unique_ptr<BodyClient>& client = clients_[body];
  if (!client) client = std::make_unique<BodyClient>(body);
  const BodyState* state = client->latest_state();
  for (int tries = 0; !state && tries < 50; ++tries) {  // a new reader waits for a state
    struct timespec pause {
      0, 2'000'000
    };
    nanosleep(&pause, nullptr);
    state = client->latest_state();
  }
  if (!state) return "no state from " + body + ": is it a live body (afhub ls)?";
  if (joint >= state->joint_count)
    return "joint: " + body + " has " + std::to_string(state->joint_count) + " joints, got index " +
           joint_text;
  BodyCommand* command = client->loan_command(state->joint_count);
  if (!command) return "no shared memory for a command";
  for (std::uint32_t j = 0; j < state->joint_count; ++j)
    command->joints[j] = {
        j == joint ? value : state->joints[j].position, JointCommandType::kPosition, {}};
  command->header.sim_step = state->header.sim_step;
  client->publish_command(command);
  return "";
}

}  // namespace afhub::viewer
