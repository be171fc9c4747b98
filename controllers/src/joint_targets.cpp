// Joint-space controllers (see joint_targets.hpp).
#include "afhub/controllers/joint_targets.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <numbers>
#include <sstream>

#include "afhub/shm_layout/error.hpp"
#include "afhub/yaml/input_file.hpp"
#include "afhub/yaml/number_text.hpp"

namespace afhub {

ControllerCycle joint_position_controller(JointTargetFunction targets) {
  struct Memory {
    bool started = false;
    double start_time_s = 0.0;
    std::uint64_t last_step = 0;
    std::uint32_t physics_pid = 0;
    JointArray initial{};
    JointArray targets{};
  };
  auto memory = std::make_shared<Memory>();
  return [memory, targets = std::move(targets)](const BodyState& state, BodyCommand& command) {
    Memory& m = *memory;
    const std::uint32_t count = std::min<std::uint32_t>(state.joint_count, kMaxJointsPerBody);
    // Simulated time jumped back (`afhub world reset`) or another physics publishes
    // (a restart): the trajectory starts again from where the joints are now,
    // ramping in, rather than from a time before its start.
    const bool jumped = state.header.sim_step < m.last_step ||
                        state.header.sim_time_s < m.start_time_s ||
                        state.header.publisher_pid != m.physics_pid;
    m.last_step = state.header.sim_step;
    m.physics_pid = state.header.publisher_pid;
    if (!m.started || jumped) {
      m.started = true;
      m.start_time_s = state.header.sim_time_s;
      for (std::uint32_t j = 0; j < count; ++j) m.initial[j] = state.joints[j].position;
    }
    targets(state.header.sim_time_s - m.start_time_s, m.initial, count, m.targets);
    command.joint_count = count;
    for (std::uint32_t j = 0; j < count; ++j) {
      command.joints[j].type = JointCommandType::kPosition;
      command.joints[j].value = m.targets[j];
    }
  };
}

JointTargetFunction hold_targets() {
  return [](double, const JointArray& initial, std::uint32_t count, JointArray& targets) {
    std::copy_n(initial.begin(), count, targets.begin());
  };
}

JointTargetFunction sine_targets(double amplitude_rad, double period_s, std::vector<int> joints) {
  return [amplitude_rad, period_s, joints = std::move(joints)](
             double t_s, const JointArray& initial, std::uint32_t count, JointArray& targets) {
    std::copy_n(initial.begin(), count, targets.begin());
    const double amplitude = amplitude_rad * std::min(1.0, t_s / period_s);
    const double angle = 2.0 * std::numbers::pi * t_s / period_s;
    const std::size_t moving = joints.empty() ? count : joints.size();
    for (std::size_t k = 0; k < moving; ++k) {
      const std::size_t j = joints.empty() ? k : static_cast<std::size_t>(joints[k]);
      if (j >= count) continue;
      const double phase =
          2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(moving);
      targets[j] = initial[j] + amplitude * std::sin(angle + phase);
    }
  };
}

namespace {

constexpr std::uintmax_t kMaxTrajectoryFileBytes = 1u << 30;

std::vector<std::string> split_fields(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream stream(line);
  for (std::string field; std::getline(stream, field, ',');) fields.push_back(field);
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

}  // namespace

JointTrajectory read_trajectory_csv(const std::string& path) {
  // A regular file of a bounded size (not /dev/zero, which never ends): an hour of
  // seven joints at 1 kHz is about 300 MB.
  yaml::check_input_file(path, kMaxTrajectoryFileBytes, "a trajectory (CSV)");
  std::ifstream in(path);
  if (!in) throw Error(path + ": error: cannot open the trajectory file");
  JointTrajectory trajectory;
  bool header_allowed = true;  // the first line may name the columns
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos || line[0] == '#') continue;
    const std::string where = path + ":" + std::to_string(number) + ": error: ";
    const std::vector<std::string> fields = split_fields(line);
    if (header_allowed && !yaml::parse_finite(fields[0])) {
      header_allowed = false;
      continue;
    }
    header_allowed = false;
    std::vector<double> values;
    for (std::size_t f = 0; f < fields.size(); ++f) {
      const std::optional<double> value = yaml::parse_finite(fields[f]);
      if (!value)
        throw Error(where + "column " + std::to_string(f + 1) + " is '" + fields[f] +
                    "', not a finite decimal number; each row is time,q0,q1,... in seconds and "
                    "rad or m");
      values.push_back(*value);
    }
    if (values.size() < 2)
      throw Error(where + "a row needs a time and at least one joint position");
    if (values.size() - 1 > kMaxJointsPerBody)
      throw Error(where + "more than " + std::to_string(kMaxJointsPerBody) + " joints");
    if (!trajectory.rows.empty() && values.size() - 1 != trajectory.rows.front().size())
      throw Error(where + "this row has " + std::to_string(values.size() - 1) +
                  " joint positions, the first had " +
                  std::to_string(trajectory.rows.front().size()));
    if (!trajectory.times_s.empty() && values[0] <= trajectory.times_s.back())
      throw Error(where + "time " + fields[0] + " does not increase; times must be increasing");
    trajectory.times_s.push_back(values[0]);
    trajectory.rows.emplace_back(values.begin() + 1, values.end());
  }
  if (trajectory.rows.empty())
    throw Error(path + ": error: no trajectory rows; expected lines of time,q0,q1,...");
  return trajectory;
}

JointTargetFunction track_targets(JointTrajectory trajectory) {
  return [trajectory = std::move(trajectory)](double t_s, const JointArray& initial,
                                              std::uint32_t count, JointArray& targets) {
    std::copy_n(initial.begin(), count, targets.begin());
    const std::vector<double>& times = trajectory.times_s;
    // The segment [times[i - 1], times[i]] holding t, clamped to the ends.
    const std::size_t i =
        static_cast<std::size_t>(std::upper_bound(times.begin(), times.end(), t_s) - times.begin());
    const std::size_t after = std::min(i, times.size() - 1);
    const std::size_t before = i == 0 ? 0 : i - 1;
    const double span = times[after] - times[before];
    const double blend = span > 0.0 ? std::clamp((t_s - times[before]) / span, 0.0, 1.0) : 0.0;
    const std::vector<double>& a = trajectory.rows[before];
    const std::vector<double>& b = trajectory.rows[after];
    for (std::size_t j = 0; j < a.size() && j < count; ++j)
      targets[j] = a[j] + blend * (b[j] - a[j]);
  };
}

}  // namespace afhub
