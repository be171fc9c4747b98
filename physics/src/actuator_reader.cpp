// ADF constraint actuators (ACTUATOR blocks): the parent body, the point that
// holds what touches it, and the constraint's impulse and tau.
#include "adf_blocks.hpp"

namespace afhub::physics::adf {
namespace {

const std::set<std::string> kActuatorKeys = {
    "name",         "namespace",         "type",   "parent",
    "location",     "max impulse",       "tau",    "visible",
    "visible size", "publish frequency", "plugins"};

}  // namespace

ActuatorSpec read_actuator(const FileReader& file, const YAML::Node& block,
                           const std::string& identifier, PendingParent& pending) {
  ActuatorSpec actuator;
  read_block_head(file, block, identifier, kActuatorKeys, "actuator", actuator);
  const YAML::Node type = file.require(block, "type", actuator.where);
  if (lower(file.text(type, "type")) != "constraint")
    fail(file.at(type), "unknown actuator type '" + type.Scalar() + "'; use Constraint");
  read_parent(file, block, actuator.where, pending);
  if (YAML::Node location = block["location"])
    actuator.location = file.placement(location, "location");
  if (YAML::Node impulse = block["max impulse"])
    actuator.max_impulse = positive(file, impulse, "max impulse");
  if (YAML::Node tau = block["tau"]) actuator.tau = positive(file, tau, "tau");
  return actuator;
}

}  // namespace afhub::physics::adf
