// Joint-space controllers shipped with `afhub ctl`: each joint of a body is sent a
// position target every cycle, computed from the simulated time since the
// controller's first state and the joint positions in that state.
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "afhub/controllers/controller.hpp"
#include "afhub/shm_layout/limits.hpp"

namespace afhub {

using JointArray = std::array<double, kMaxJointsPerBody>;

// Fills `targets[0, count)` for time `t_s` since the first state, whose joint
// positions were `initial`. Called in the real-time loop: no allocation.
using JointTargetFunction = std::function<void(double t_s, const JointArray& initial,
                                               std::uint32_t count, JointArray& targets)>;

// A ControllerCycle sending position commands from `targets` for every joint of the
// body. When simulated time jumps back (a reset: the step decreases) or another
// physics process publishes the state (a restart), it starts over: time 0 and the
// joint positions of that state as `initial`, so that the targets ramp in again.
ControllerCycle joint_position_controller(JointTargetFunction targets);

// Holds every joint where it was.
JointTargetFunction hold_targets();

// Joint i follows initial_i + A sin(2 pi t / period + phase_i), the phases spread
// evenly over the selected joints (all when `joints` is empty); the amplitude ramps
// up over the first period so no target jumps. Other joints hold.
JointTargetFunction sine_targets(double amplitude_rad, double period_s, std::vector<int> joints);

// A joint trajectory: times in seconds, increasing; one row of joint positions per time.
struct JointTrajectory {
  std::vector<double> times_s;
  std::vector<std::vector<double>> rows;
};

// Reads "time,q0,q1,..." rows (an optional header line first). Throws afhub::Error
// with "file:line: error: ..." for anything malformed.
JointTrajectory read_trajectory_csv(const std::string& path);

// Follows the trajectory, interpolating linearly; before the first time and after
// the last it holds the first and last rows. Joints beyond the columns hold.
JointTargetFunction track_targets(JointTrajectory trajectory);

}  // namespace afhub
