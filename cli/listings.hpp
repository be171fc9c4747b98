// The renderings of `afhub ls` and `afhub status`, apart from the channels they
// read: each takes payloads that passed check_payload (every count within its
// array) and returns the text to print, so they can be tested without a hub.
#pragma once

#include <string>
#include <vector>

#include "afhub/shm_layout/catalog.hpp"
#include "afhub/shm_layout/health.hpp"
#include "afhub/shm_layout/loop_stats.hpp"
#include "afhub/shm_layout/world.hpp"

namespace afhub::cli {

// `afhub ls`: a table of the catalog's bodies (or a hint when there are none), and its JSON.
std::string ls_text(const BodyList& catalog);
std::string ls_json(const BodyList& catalog);

// `afhub status`: the hub's health, the catalog, the world state (nullptr when no
// simulation runs) and the loops, as text and as one JSON object.
std::string status_text(const Health& health, const BodyList& catalog, const WorldState* world,
                        const std::vector<LoopStats>& loops);
std::string status_json(const Health& health, const BodyList& catalog, const WorldState* world,
                        const std::vector<LoopStats>& loops);

}  // namespace afhub::cli
