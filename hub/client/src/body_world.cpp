// The world of a body's physics (see body_world.hpp).
#include "afhub/hub/body_world.hpp"

#include <string>

#include "afhub/shm_layout/channel_names.hpp"

namespace afhub {

BodyWorld::BodyWorld(std::string_view body_channel) {
  const auto add = [&](std::string_view name_space) {
    worlds_.push_back(std::make_unique<LatestReader<WorldState>>(
        ChannelId{std::string(kService), world_instance(name_space), std::string(kStateEvent)}));
  };
  add({});
  for (std::size_t slash = body_channel.find('/'); slash != std::string_view::npos;
       slash = body_channel.find('/', slash + 1))
    add(body_channel.substr(0, slash));
}

const WorldState* BodyWorld::of(const BodyState& body) noexcept {
  for (auto& world : worlds_)
    if (const WorldState* state = world->latest();
        state && state->header.publisher_pid == body.header.publisher_pid)
      return state;
  return nullptr;
}

}  // namespace afhub
