// Joint gains from outside the model files (see gain_overrides.hpp).
#include "afhub/physics/gain_overrides.hpp"

#include <cmath>
#include <string>

#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"

namespace afhub::physics {
namespace {

// "a/b/c" names "a/b/c" itself, and "b/c" or "c" name it by their last parts.
bool names(const std::string& channel, const std::string& wanted) {
  if (channel == wanted) return true;
  return channel.size() > wanted.size() && channel.ends_with(wanted) &&
         channel[channel.size() - wanted.size() - 1] == '/';
}

std::string listed(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
  return text;
}

}  // namespace

void require_valid_gains(const Pid& gains, std::string_view option) {
  for (const double gain : {gains.p, gains.i, gains.d})
    if (!std::isfinite(gain) || gain < 0.0)
      throw Error(std::string(option) + ": gains P, I and D must be finite and not negative, got " +
                  std::to_string(gains.p) + ", " + std::to_string(gains.i) + ", " +
                  std::to_string(gains.d));
}

std::size_t set_default_gains(Model& model, const Pid& gains) {
  require_valid_gains(gains, "--default-gains");
  std::size_t set = 0;
  for (JointSpec& joint : model.joints)
    // Passive joints and joints without an axis take no position command: no gains.
    if (joint.gains_from == GainSource::kAmbfDefault && !joint.passive &&
        has_joint_axis(joint.type)) {
      joint.controller = gains;
      joint.gains_from = GainSource::kCommandLine;
      ++set;
    }
  return set;
}

std::vector<std::size_t> joints_named(const Model& model, std::string_view target,
                                      std::string_view option) {
  const std::string wanted = body_channel_name("", target);
  if (wanted.empty())
    throw Error(std::string(option) + ": no joint or body named: give one, e.g. " +
                std::string(option) + " baselink-yawlink=1000,0,10");
  // Exact names first, so that "arm/base" is not ambiguous with "copy/arm/base".
  for (const bool exact : {true, false}) {
    std::vector<std::string> found;
    std::vector<std::size_t> joints;
    for (std::size_t j = 0; j < model.joints.size(); ++j) {
      const std::string& channel = model.joints[j].channel;
      if (exact ? channel == wanted : names(channel, wanted)) {
        found.push_back("joint " + channel);
        joints = {j};
      }
    }
    for (std::size_t b = 0; b < model.bodies.size(); ++b) {
      const std::string& channel = model.bodies[b].channel;
      if (exact ? channel == wanted : names(channel, wanted)) {
        found.push_back("body " + channel);
        joints.assign(model.descendant_joints[b].begin(), model.descendant_joints[b].end());
      }
    }
    if (found.size() > 1)
      throw Error(std::string(option) + ": '" + wanted + "' is ambiguous: it names " +
                  listed(found) + "; give more of the name");
    if (found.size() == 1) {
      if (joints.empty())
        throw Error(std::string(option) + ": " + found.front() +
                    " has no joints below it to give gains to");
      return joints;
    }
  }
  std::vector<std::string> joints;
  for (const JointSpec& joint : model.joints) joints.push_back(joint.channel);
  throw Error(std::string(option) + ": no joint or body is named '" + wanted +
              "'; joints: " + listed(joints) + " (or a body: every joint below it)");
}

void set_gains(Model& model, std::string_view target, const Pid& gains, std::string_view option) {
  require_valid_gains(gains, option);
  for (const std::size_t j : joints_named(model, target, option)) {
    model.joints[j].controller = gains;
    model.joints[j].gains_from = GainSource::kCommandLine;
  }
}

}  // namespace afhub::physics
