// Joint PID gains given from outside the model files (`afhub run --default-gains` and
// `--gains`): AMBF's robots often give their joints none, and AMBF's default
// (P 10, I 0, D 1) barely moves a real arm. The stability cap (JointModel) still
// applies to gains given here.
#pragma once

#include <cstddef>
#include <string_view>
#include <vector>

#include "afhub/physics/model.hpp"

namespace afhub::physics {

// Throws afhub::Error naming `option` unless P, I and D are finite and not negative.
void require_valid_gains(const Pid& gains, std::string_view option);

// Every joint whose file gives no `controller` takes `gains` (passive joints and joints
// without an axis, which take no position command, are left alone); returns how many did.
std::size_t set_default_gains(Model& model, const Pid& gains);

// The joints `target` names: a joint (its channel, "ambf/env/ecm/baselink-yawlink",
// or its last parts, "baselink-yawlink"; spaces removed as in channel names) or a
// body (every joint below it). Throws afhub::Error naming `option`, with the
// candidates, when `target` names nothing or more than one joint or body.
std::vector<std::size_t> joints_named(const Model& model, std::string_view target,
                                      std::string_view option);

// The joints `target` names (joints_named) take `gains`, over their file's.
void set_gains(Model& model, std::string_view target, const Pid& gains, std::string_view option);

}  // namespace afhub::physics
