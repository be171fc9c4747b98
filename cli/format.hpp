// Text and JSON renderings of payloads, and parsing of numeric lists from flags.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "afhub/hub/bodies.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/catalog.hpp"
#include "afhub/shm_layout/device.hpp"

namespace afhub::cli {

// The parts of a body state to show (`afhub echo --fields`).
struct StateFields {
  bool pose = true;     // position and orientation
  bool twist = true;    // linear and angular velocity
  bool wrench = true;   // applied force and torque
  bool contact = true;  // contact force and torque, and the contact points' count
  bool joints = true;   // joint positions (with their names in JSON)
  bool joint_velocities = true;
  bool joint_efforts = true;
  bool mass = true;  // mass and principal inertia
};
// What `--fields` takes, comma-separated.
inline constexpr const char* kStateFieldNames =
    "pose, twist, wrench, contact, joints, joint_velocities, joint_efforts, mass, all";
// Parses "pose,twist,joints": the fields named; throws afhub::Error listing the valid ones.
StateFields parse_state_fields(const std::string& text);
// What the text form shows unless told otherwise.
StateFields default_text_fields();

// One JSON line for a body state; joint names come from the catalog entry. The
// header's fields (body, sequence, step, times, publisher) are always there.
std::string state_json(const BodyEntry& entry, const BodyState& state,
                       const StateFields& fields = {});
// One human-readable line for a body state.
std::string state_text(const BodyEntry& entry, const BodyState& state,
                       const StateFields& fields = default_text_fields());

// One JSON line, or one human-readable line, for a device's state: pose, velocity,
// gripper, buttons, and the force the driver applies now with why (the gate).
std::string device_state_json(const BodyEntry& entry, const DeviceState& state);
std::string device_state_text(const BodyEntry& entry, const DeviceState& state);

// A measured rate for a table: "-" when there is no measurement yet (0 or less).
std::string rate_text(double rate_hz);
bool rate_measured(double rate_hz);

// The non-empty items of a comma-separated list: "a,,b" -> {a, b}.
std::vector<std::string> split_commas(const std::string& text);

// Parses "a,b,c" into finite numbers; throws afhub::Error naming `flag` when a value
// is not a number, is NaN or Inf, or when the count is not `expected` (0: any count).
std::vector<double> parse_numbers(std::string_view text, std::string_view flag,
                                  std::size_t expected);

}  // namespace afhub::cli
