// A body command out of shared memory into the physics core's input. The command
// passed check_payload (its counts within their arrays); the input is then checked
// against the body (Simulation::input_problem) before it is applied.
#pragma once

#include "afhub/physics/body_input.hpp"
#include "afhub/shm_layout/body_command.hpp"

namespace afhub::physics {

// Copied once, so that a writer cannot change it between the check and its use.
// Counts are copied as written (input_problem refuses those beyond the body's);
// entries up to capacity.
void to_input(const BodyCommand& command, BodyInput& input) noexcept;

}  // namespace afhub::physics
