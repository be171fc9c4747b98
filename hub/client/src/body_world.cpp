// The world of a body's physics (see body_world.hpp).
#include "afhub/hub/body_world.hpp"

#include <string>

#include "afhub/shm_layout/channel_names.hpp"

namespace afhub {

BodyWorld::BodyWorld(std::string_view body_channel) {
  const auto add = [&](std::string_view name_space) {
    worlds_.push_back(
        {std::string(name_space),
         std::make_unique<LatestReader<WorldState>>(ChannelId{
             std::string(kService), world_instance(name_space), std::string(kStateEvent)})});
    worlds_.back().reader->latest();
  };
  for (std::size_t slash = body_channel.rfind('/'); slash != std::string_view::npos && slash > 0;
       slash = body_channel.rfind('/', slash - 1))
    add(body_channel.substr(0, slash));
  add({});
}

BodyWorld::Found BodyWorld::find(const BodyState& body) noexcept {
  for (Candidate& world : worlds_)
    if (const WorldState* state = world.reader->latest();
        state && state->header.publisher_pid == body.header.publisher_pid &&
        state->header.sim_step + 2 >= body.header.sim_step &&
        body.header.sim_step + 2 >= state->header.sim_step)
      return {state, &world.name_space};
  return {};
}

const WorldState* BodyWorld::of(const BodyState& body) noexcept {
  return find(body).state;
}

const std::string* BodyWorld::name_space_of(const BodyState& body) noexcept {
  return find(body).name_space;
}

}  // namespace afhub
