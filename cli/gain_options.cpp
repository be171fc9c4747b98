// Joint gains from the command line (see gain_options.hpp).
#include "gain_options.hpp"

#include <cmath>
#include <cstdio>
#include <string>

#include "afhub/physics/gain_overrides.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/yaml/yaml_reader.hpp"
#include "format.hpp"

namespace afhub::cli {

void add_gain_options(CLI::App* command, GainOptions& options) {
  command->add_option(
      "--default-gains", options.default_gains,
      "P,I,D for every joint whose file gives no `controller` (AMBF's default is P 10, I 0, "
      "D 1, which barely moves a real arm): --default-gains 1000,0,10. `afhub check` lists "
      "those joints");
  command
      ->add_option("--gains", options.gains,
                   "NAME=P,I,D: these gains for a joint, or for every joint below a body, over "
                   "its file's; NAME as in channel names or their last parts "
                   "(--gains ecm/baselink=1000,0,10, --gains baselink-yawlink=2000,0,20); "
                   "repeat for more, a later one wins")
      ->allow_extra_args(false);
}

physics::Pid parse_gains(std::string_view text, std::string_view option) {
  const std::string usage = std::string(option) +
                            " takes P,I,D: three numbers from 0 to 1e9 (a model file's bound), "
                            "e.g. 1000,0,10";
  std::vector<double> numbers;
  try {
    numbers = parse_numbers(text, option, 3);
  } catch (const Error&) {
    throw Error(usage + "; got '" + std::string(text) + "'");
  }
  for (const double number : numbers)
    if (number < 0.0 || number > yaml::kMaxMagnitude)
      throw Error(usage + "; got '" + std::string(text) + "'");
  return {numbers[0], numbers[1], numbers[2]};
}

Vec3 parse_gravity(std::string_view text, std::vector<std::string>& warnings) {
  const std::vector<double> g = parse_numbers(text, "--gravity", 3);
  for (const double value : g)
    if (std::abs(value) > yaml::kMaxMagnitude)
      throw Error("--gravity: " + std::string(text) +
                  " is beyond a model file's bound of 1e9 m/s^2 per axis");
  if (std::hypot(g[0], g[1], g[2]) > 98.1)
    warnings.push_back("warning: --gravity " + std::string(text) +
                       " is more than 10 g: it is in m/s^2 (Earth's is 0,0,-9.81); check its unit");
  return {g[0], g[1], g[2]};
}

void apply_gain_options(physics::Model& model, const GainOptions& options) {
  if (!options.default_gains.empty())
    physics::set_default_gains(model, parse_gains(options.default_gains, "--default-gains"));
  for (const std::string& entry : options.gains) {
    const std::size_t equals = entry.rfind('=');
    if (equals == std::string::npos || equals == 0)
      throw Error(
          "--gains takes NAME=P,I,D (a joint or a body, then its gains), e.g. "
          "--gains baselink-yawlink=1000,0,10; got '" +
          entry + "'");
    physics::set_gains(model, entry.substr(0, equals),
                       parse_gains(std::string_view(entry).substr(equals + 1), "--gains"),
                       "--gains");
  }
}

}  // namespace afhub::cli
