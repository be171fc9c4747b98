// Text and JSON renderings of payloads, and parsing of numeric lists from flags.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/catalog.hpp"

namespace afhub::cli {

// One JSON line for a body state; joint names come from the catalog entry.
std::string state_json(const BodyInfo& info, const BodyState& state);
// One human-readable line for a body state.
std::string state_text(const BodyInfo& info, const BodyState& state);

// Parses "a,b,c" into finite numbers; throws afhub::Error naming `flag` when a value
// is not a number, is NaN or Inf, or when the count is not `expected` (0: any count).
// The non-empty items of a comma-separated list: "a,,b" -> {a, b}.
std::vector<std::string> split_commas(const std::string& text);

std::vector<double> parse_numbers(std::string_view text, std::string_view flag,
                                  std::size_t expected);

}  // namespace afhub::cli
