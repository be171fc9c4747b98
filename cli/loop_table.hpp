// The table of live loops shared by `afhub status` and `afhub top`, and its JSON.
#pragma once

#include <string>
#include <vector>

#include "afhub/hub/json_writer.hpp"
#include "afhub/shm_layout/loop_stats.hpp"

namespace afhub::cli {

// One line per loop: process, what it does, rate, wake-up and compute percentiles,
// overruns, late commands and its real-time settings.
std::string loop_table(const std::vector<LoopStats>& loops);
void loop_json(JsonWriter& json, const std::vector<LoopStats>& loops);

}  // namespace afhub::cli
