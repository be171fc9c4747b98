// `--default-gains P,I,D` and `--gains NAME=P,I,D`, for `afhub run` and `afhub check`:
// joint PID gains given from outside the model files (physics/gain_overrides.hpp); and
// `--gravity`, the other value they take over the files'.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "afhub/physics/model.hpp"

namespace afhub::cli {

struct GainOptions {
  std::string default_gains;       // "P,I,D"
  std::vector<std::string> gains;  // "NAME=P,I,D", one per use of --gains
};

void add_gain_options(CLI::App* command, GainOptions& options);

// "1000,0,10" as gains; throws afhub::Error naming `option` unless it is three numbers
// from 0 to a model file's bound (1e9).
physics::Pid parse_gains(std::string_view text, std::string_view option);

// --default-gains first (the joints whose file gives no `controller`), then each
// --gains in order (a later one wins over an earlier one and over the file's).
void apply_gain_options(physics::Model& model, const GainOptions& options);

// `--gravity x,y,z` in m/s^2, each within a model file's bound (1e9); more than 10 g is
// added to `warnings` (as a file's gravity is warned of).
Vec3 parse_gravity(std::string_view text, std::vector<std::string>& warnings);

}  // namespace afhub::cli
