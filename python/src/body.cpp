// afhub.Body and afhub.State (see body.hpp).
#include "body.hpp"

#include <pybind11/stl.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <new>

#include "afhub/hub/hub_health.hpp"
#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/sample_waiter.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/shm_layout/error.hpp"
#include "errors.hpp"

namespace afhub::python {

// One allocation: the state at its real size, then its joints' three columns.
State::State(const BodyState& sample)
    : state_(static_cast<BodyState*>(std::malloc(body_state_bytes(sample.joint_count) +
                                                 3 * sample.joint_count * sizeof(double))),
             [](BodyState* state) { std::free(state); }) {
  if (!state_) throw std::bad_alloc();
  const std::size_t bytes = body_state_bytes(sample.joint_count);
  std::memcpy(state_.get(), &sample, bytes);
  auto* columns = reinterpret_cast<double*>(reinterpret_cast<char*>(state_.get()) + bytes);
  const std::uint32_t count = sample.joint_count;
  for (std::uint32_t j = 0; j < count; ++j) {
    columns[j] = sample.joints[j].position;
    columns[count + j] = sample.joints[j].velocity;
    columns[2 * count + j] = sample.joints[j].effort;
  }
}

py::object State::joint_column(std::size_t member) const {
  static_assert(offsetof(JointSample, velocity) == sizeof(double) &&
                offsetof(JointSample, effort) == 2 * sizeof(double));
  const std::size_t column = member / sizeof(double);
  if (!columns_[column]) {
    const auto* first = reinterpret_cast<const double*>(
        reinterpret_cast<const char*>(state_.get()) + body_state_bytes(state_->joint_count));
    py::capsule owner(new std::shared_ptr<BodyState>(state_),
                      [](void* kept) { delete static_cast<std::shared_ptr<BodyState>*>(kept); });
    columns_[column] =
        view(first + column * state_->joint_count, state_->joint_count, sizeof(double), owner);
  }
  return columns_[column];
}

Body::Body(const std::string& name, double wait_s)
    : entry_([&] {
        BodyEntry entry = wait_for_entry(name, wait_s, "body");
        if (entry.info.kind == ChannelKind::kDevice)
          throw Error("'" + std::string(name_of(entry.info.channel)) +
                      "' is a device, not a body: open it with afhub.Device");
        return entry;
      }()),
      channel_(name_of(entry_.info.channel)),
      client_(entry_),
      pid_(static_cast<std::uint32_t>(getpid())) {
  // Before the first loan, as every publisher: a script must not starve a running physics.
  py::gil_scoped_release release;
  require_chunks({written_as_slot(body_command_bytes(entry_.info.joint_count))},
                 "this Python client (commanding " + channel_ + ")");
}

py::object Body::read(double wait_s) {
  require_hub();
  const std::int64_t give_up = deadline_after(wait_s, "wait_s");  // checked, waited or not
  const BodyState* sample = client_.latest_state();
  if (!sample && wait_s > 0.0) {
    SignalWatch signals;
    {
      py::gil_scoped_release release;
      while (!(sample = client_.latest_state()) && monotonic_ns() < give_up && !signals.pending())
        sleep_until_ns(monotonic_ns() + 1'000'000);
    }
    signals.raise_if_pending();
  }
  if (!sample) return py::none();
  // The same sample as last time (by its writer and sequence): the same State.
  const PayloadHeader& header = sample->header;
  if (last_read_ && header.publisher_pid == last_read_header_.publisher_pid &&
      header.sequence == last_read_header_.sequence &&
      header.publish_stamp_ns == last_read_header_.publish_stamp_ns)
    return last_read_;
  last_read_ = py::cast(State(*sample));
  last_read_header_ = header;
  return last_read_;
}

State Body::wait_next(std::optional<std::uint64_t> after_step, double timeout_s) {
  require_hub();
  const std::int64_t give_up = deadline_after(timeout_s, "timeout_s");
  const BodyState* sample = nullptr;
  SignalWatch signals;
  {
    py::gil_scoped_release release;
    SampleWaiter waiter;
    waiter.attach(client_.state_reader());
    for (;;) {
      sample = client_.latest_state();
      if (sample && (after_step ? sample->header.sim_step > *after_step : client_.state_updated()))
        break;
      const std::int64_t left = give_up - monotonic_ns();
      if (left <= 0 || hub_lost() || signals.pending()) {
        sample = nullptr;
        break;
      }
      waiter.wait(std::min<std::int64_t>(left, 10'000'000));
    }
  }
  signals.raise_if_pending();
  if (!sample) {
    require_hub();
    throw Error("no new state came from " + channel_ + " in " +
                py::str(py::float_(timeout_s)).cast<std::string>() +
                " s: is its simulation running (or paused, or waiting for lockstep clients)? "
                "`afhub world resume` runs a paused one");
  }
  return State(*sample);
}

void Body::check_refused() {
  const BodyState* state = client_.latest_state();
  if (!state) return;
  // The first state seen: published before this body's first command (by this physics,
  // or by one an earlier test or script stopped), it cannot carry a refusal of it, and
  // only sets the count; published after, its refusals are new when they name this process.
  const bool new_refusal = refusals_known_
                               ? state->refused_commands != refusals_seen_
                               : first_command_ns_ != 0 &&
                                     state->header.publish_stamp_ns >= first_command_ns_ &&
                                     state->refused_commands > 0;
  refusals_seen_ = state->refused_commands;
  refusals_known_ = true;
  if (!new_refusal || state->refused_command_pid != pid_) return;
  throw CommandRefused("the physics refused the command for " + channel_ + ": " +
                       std::string(name_of(state->refusal_reason)) +
                       " (nothing of it was applied). Command values within the body's bounds; "
                       "`afhub echo " +
                       channel_ + "` shows its joints now");
}

template <class Fill>
void Body::send(std::uint32_t joint_count, const Fill& fill) {
  if (joint_count > entry_.info.joint_count)
    throw py::value_error("the command gives " + std::to_string(joint_count) +
                          " joint values but body " + channel_ + " has " +
                          std::to_string(entry_.info.joint_count) + " joints (see `afhub ls`)");
  require_hub();
  check_refused();
  BodyCommand* command = client_.loan_command(joint_count);
  if (!command) throw Error("shared memory is exhausted: the command was not sent");
  fill(*command);
  // A command answers the newest state it has seen.
  if (const BodyState* state = client_.latest_state()) {
    command->header.sim_step = state->header.sim_step;
    command->header.sim_time_s = state->header.sim_time_s;
  }
  command->lockstep = lockstep_;
  if (first_command_ns_ == 0) first_command_ns_ = monotonic_ns();
  client_.publish_command(command);
}

namespace {

JointCommandType joint_type_of(const py::handle& item) {
  if (py::isinstance<JointCommandType>(item)) return item.cast<JointCommandType>();
  if (py::isinstance<py::str>(item)) {
    const auto text = item.cast<std::string>();
    if (text == "position") return JointCommandType::kPosition;
    if (text == "velocity") return JointCommandType::kVelocity;
    if (text == "effort") return JointCommandType::kEffort;
  }
  throw py::value_error(
      "a joint type is afhub.JointType.POSITION, VELOCITY or EFFORT (or "
      "'position', 'velocity', 'effort'), not " +
      py::repr(item).cast<std::string>());
}

// A Cartesian part of a command: at most one mode, as AMBF's afCommand carries one.
struct Cartesian {
  std::optional<Vec3> force, torque, position, linear, angular;
  std::optional<Quaternion> orientation;
};

Cartesian cartesian_of(const py::object& force, const py::object& torque,
                       const py::object& position, const py::object& orientation,
                       const py::object& linear, const py::object& angular) {
  Cartesian c;
  if (!force.is_none()) c.force = to_vec3(force, "force");
  if (!torque.is_none()) c.torque = to_vec3(torque, "torque");
  if (!position.is_none()) c.position = to_vec3(position, "position");
  if (!orientation.is_none()) c.orientation = to_quaternion(orientation, "orientation");
  if (!linear.is_none()) c.linear = to_vec3(linear, "linear_velocity");
  if (!angular.is_none()) c.angular = to_vec3(angular, "angular_velocity");
  const int modes = (c.force || c.torque) + (c.position || c.orientation) + (c.linear || c.angular);
  if (modes > 1)
    throw py::value_error(
        "a command carries one Cartesian mode: force/torque, position/orientation or "
        "linear_velocity/angular_velocity; give one");
  return c;
}

void register_state(py::module_& module) {
  const auto vec = [](std::size_t offset) {
    return [offset](py::object self) {
      const auto& state = *self.cast<const State&>();
      const auto* first =
          reinterpret_cast<const double*>(reinterpret_cast<const char*>(&state) + offset);
      return view(first, 3, sizeof(double), self);
    };
  };
  const auto joints = [](std::size_t member) {
    return [member](const State& state) { return state.joint_column(member); };
  };
  py::class_<State>(module, "State",
                    "One state of a body, copied out of shared memory when read (one small "
                    "copy): its arrays are read-only numpy views on that copy, valid for as "
                    "long as they are held. SI units, world frame.")
      .def_property_readonly(
          "step", [](const State& s) { return s->header.sim_step; },
          "The simulation step it describes.")
      .def_property_readonly(
          "time", [](const State& s) { return s->header.sim_time_s; }, "Simulated time, s.")
      .def_property_readonly(
          "stamp_ns", [](const State& s) { return s->header.publish_stamp_ns; },
          "When it was published: CLOCK_MONOTONIC ns (time.monotonic_ns()).")
      .def_property_readonly(
          "step_due_ns", [](const State& s) { return s->step_due_ns; },
          "When its step was due on the physics' clock (CLOCK_MONOTONIC ns); 0 when the "
          "physics is not paced by the clock (--fast) or the state came from another machine.")
      .def_property_readonly(
          "command_answered_step", [](const State& s) { return s->command_answered_step; },
          "The step whose state the command in force during this step answered; -1 with "
          "none in force. step - 1 - command_answered_step: how many steps old that state "
          "was.")
      .def_property_readonly(
          "sequence", [](const State& s) { return s->header.sequence; },
          "Its publisher's sequence number.")
      .def_property_readonly("publisher_pid",
                             [](const State& s) { return s->header.publisher_pid; })
      .def_property_readonly("position", vec(offsetof(BodyState, pose.position_m)),
                             "x, y, z (m) of the body's mesh frame.")
      .def_property_readonly(
          "orientation",
          [](py::object self) {
            const auto& q = self.cast<const State&>()->pose.orientation;
            return view(&q.x, 4, sizeof(double), self);
          },
          "Unit quaternion x, y, z, w (Hamilton), as AMBF and ROS order it.")
      .def_property_readonly("linear_velocity", vec(offsetof(BodyState, twist.linear_mps)), "m/s")
      .def_property_readonly("angular_velocity", vec(offsetof(BodyState, twist.angular_radps)),
                             "rad/s")
      .def_property_readonly("force", vec(offsetof(BodyState, wrench.force_n)),
                             "The force applied in the last step, N.")
      .def_property_readonly("torque", vec(offsetof(BodyState, wrench.torque_nm)),
                             "The torque applied in the last step, N m.")
      .def_property_readonly("contact_force", vec(offsetof(BodyState, contact_wrench.force_n)),
                             "The net force of the last step's contacts, N.")
      .def_property_readonly("contact_torque", vec(offsetof(BodyState, contact_wrench.torque_nm)),
                             "The contacts' net torque about the mesh frame's origin, N m.")
      .def_property_readonly("contact_count", [](const State& s) { return s->contact_count; })
      .def_property_readonly(
          "mass", [](const State& s) { return s->mass_kg; }, "kg")
      .def_property_readonly("inertia", vec(offsetof(BodyState, principal_inertia_kgm2)),
                             "Principal inertia, kg m^2.")
      .def_property_readonly(
          "joint_count", [](const State& s) { return s->joint_count; },
          "The body's descendant joints, in the catalog's order (Body.joint_names).")
      .def_property_readonly("joint_positions", joints(offsetof(JointSample, position)), "rad or m")
      .def_property_readonly("joint_velocities", joints(offsetof(JointSample, velocity)),
                             "rad/s or m/s")
      .def_property_readonly("joint_efforts", joints(offsetof(JointSample, effort)), "N m or N")
      .def_property_readonly(
          "sensor_distances",
          [](py::object self) {
            const State& s = self.cast<const State&>();
            return view(s->sensor_distances_m.data(), s->sensor_ray_count, sizeof(double), self);
          },
          "Proximity sensors' rays in file order: distance to the first hit, m, or -1.")
      .def_property_readonly(
          "sensor_ranges",
          [](py::object self) {
            const State& s = self.cast<const State&>();
            return view(s->sensor_ranges_m.data(), s->sensor_ray_count, sizeof(double), self);
          },
          "Each ray's range, m (Body.sensor_rays names its sensor).")
      .def_property_readonly(
          "refused_commands", [](const State& s) { return s->refused_commands; },
          "Commands for this body the physics refused since it started.")
      .def_property_readonly("refusal_reason",
                             [](const State& s) { return std::string(name_of(s->refusal_reason)); })
      .def("__repr__", [](const State& s) {
        return "<afhub.State step " + std::to_string(s->header.sim_step) + ", " +
               std::to_string(s->joint_count) + " joints>";
      });
}

}  // namespace

void register_body(py::module_& module) {
  py::enum_<JointCommandType>(module, "JointType", "How a joint command's value is meant.")
      .value("EFFORT", JointCommandType::kEffort, "N m or N")
      .value("POSITION", JointCommandType::kPosition, "a target, rad or m")
      .value("VELOCITY", JointCommandType::kVelocity, "a target, rad/s or m/s");
  register_state(module);

  const auto uniform = [](JointCommandType type) {
    return [type](Body& body, const py::handle& values) {
      const auto array = finite_values(values, "values");
      const auto count = static_cast<std::uint32_t>(array.size());
      const double* data = array.data();
      body.send(count, [&](BodyCommand& command) {
        for (std::uint32_t j = 0; j < count; ++j) {
          command.joints[j].type = type;
          command.joints[j].value = data[j];
        }
      });
    };
  };

  py::class_<Body>(module, "Body",
                   "One simulated body: its newest state, read in shared memory, and its "
                   "command slot.\n\nBody(name, wait_s=0): `name` is the body's channel name "
                   "or a unique suffix of it after a '/' ('arm/base', 'base'), as `afhub ls` "
                   "lists them; wait_s waits for a body whose physics is starting. Raises "
                   "afhub.Error listing the candidates for an unknown or ambiguous name.\n\n"
                   "The physics releases a body whose commands stop for its watchdog period "
                   "(0.5 s by default): send commands again and again. A Body is used by one "
                   "thread at a time.")
      .def(py::init<const std::string&, double>(), py::arg("name"), py::arg("wait_s") = 0.0)
      .def_property_readonly("channel", &Body::channel, "The body's channel name.")
      .def_property_readonly("joint_names", &Body::joint_names,
                             "The names of its descendant joints, in state and command order.")
      .def_property_readonly(
          "sensor_rays", [](const Body& body) { return body.entry().sensor_rays; },
          "Per ray of State.sensor_distances, the name of the proximity sensor it belongs to.")
      .def_property_readonly(
          "actuator_names", [](const Body& body) { return body.entry().actuator_names; },
          "Its constraint actuators, in the order of command()'s actuators flags.")
      .def_property_readonly(
          "child_names", [](const Body& body) { return body.entry().child_names; },
          "The bodies jointed directly below it (model names, without the namespace).")
      .def_property_readonly(
          "parent_name", [](const Body& body) { return body.entry().parent_name; },
          "The body it is jointed below (its model name), or '' for none.")
      .def("joint_index", &Body::joint_index, py::arg("name"),
           "The index of joint `name`; afhub.Error listing the body's joints when it has none "
           "so named.")
      .def("read", &Body::read, py::arg("wait_s") = 0.0,
           "The newest state (afhub.State), or None when none came yet (after waiting up to "
           "wait_s for the first).")
      .def("wait_next", &Body::wait_next, py::arg("after_step") = py::none(),
           py::arg("timeout_s") = 5.0,
           "Waits for a state of a step after `after_step` (or for any sample newer than the "
           "last read when None) and returns it; afhub.Error when none came within timeout_s.")
      .def(
          "command",
          [](Body& body, const py::object& joint_values, const py::object& joint_types,
             const py::object& force, const py::object& torque, const py::object& position,
             const py::object& orientation, const py::object& linear_velocity,
             const py::object& angular_velocity, const py::object& actuators) {
            const Cartesian c = cartesian_of(force, torque, position, orientation, linear_velocity,
                                             angular_velocity);
            py::array_t<double> values;
            std::vector<JointCommandType> types;
            if (!joint_values.is_none()) {
              values = finite_values(joint_values, "joint_values");
              if (joint_types.is_none())
                throw py::value_error(
                    "joint_values needs joint_types: one afhub.JointType for all, or one per "
                    "joint ('position', 'velocity', 'effort')");
              if (py::isinstance<py::str>(joint_types) ||
                  py::isinstance<JointCommandType>(joint_types)) {
                types.assign(static_cast<std::size_t>(values.size()), joint_type_of(joint_types));
              } else {
                // Read up to one past what it needs: an endless iterator ends too.
                for (const py::handle item : joint_types) {
                  types.push_back(joint_type_of(item));
                  if (types.size() > static_cast<std::size_t>(values.size())) break;
                }
                if (types.size() != static_cast<std::size_t>(values.size()))
                  throw py::value_error("joint_types gives " + std::to_string(types.size()) +
                                        " types for " + std::to_string(values.size()) +
                                        " joint_values");
              }
            }
            std::vector<std::uint8_t> actuate;
            if (!actuators.is_none()) {
              if (py::isinstance<py::str>(actuators))
                throw py::value_error("actuators takes a sequence of True/False flags");
              const py::object numpy_bool = py::module_::import("numpy").attr("bool_");
              for (const py::handle item : actuators) {
                if (actuate.size() == kMaxActuatorsPerBody)
                  throw py::value_error("actuators takes at most " +
                                        std::to_string(kMaxActuatorsPerBody) + " flags");
                if (!py::isinstance<py::bool_>(item) && !py::isinstance(item, numpy_bool))
                  throw py::value_error("actuators[" + std::to_string(actuate.size()) + "] is " +
                                        py::repr(item).cast<std::string>() + ", not True or False");
                actuate.push_back(item.cast<bool>() ? 1 : 0);
              }
            }
            // A pose given in part keeps the rest of the newest one.
            Pose pose;
            if (c.position || c.orientation) {
              if (const BodyState* state = body.client().latest_state()) pose = state->pose;
              if (c.position) pose.position_m = *c.position;
              if (c.orientation) pose.orientation = *c.orientation;
            }
            const auto count = static_cast<std::uint32_t>(types.size());
            const double* data = count ? values.data() : nullptr;
            body.send(count, [&](BodyCommand& command) {
              for (std::uint32_t j = 0; j < count; ++j) {
                command.joints[j].type = types[j];
                command.joints[j].value = data[j];
              }
              if (c.position || c.orientation) {
                command.cartesian_type = CartesianCommandType::kPosition;
                command.pose = pose;
              } else if (c.linear || c.angular) {
                command.cartesian_type = CartesianCommandType::kVelocity;
                command.twist.linear_mps = c.linear.value_or(Vec3{});
                command.twist.angular_radps = c.angular.value_or(Vec3{});
              } else {
                command.cartesian_type = CartesianCommandType::kForce;
                command.wrench.force_n = c.force.value_or(Vec3{});
                command.wrench.torque_nm = c.torque.value_or(Vec3{});
              }
              command.actuator_count = static_cast<std::uint32_t>(actuate.size());
              std::copy(actuate.begin(), actuate.end(), command.actuate.begin());
            });
          },
          py::arg("joint_values") = py::none(), py::arg("joint_types") = py::none(), py::kw_only(),
          py::arg("force") = py::none(), py::arg("torque") = py::none(),
          py::arg("position") = py::none(), py::arg("orientation") = py::none(),
          py::arg("linear_velocity") = py::none(), py::arg("angular_velocity") = py::none(),
          py::arg("actuators") = py::none(),
          "Writes one command, everything the body's command slot carries:\n"
          "  joint_values, joint_types: joints 0.. of the body (a list shorter than its joints "
          "leaves the rest uncommanded); one afhub.JointType for all, or one per joint, so "
          "position, velocity and effort mix per joint;\n"
          "  one Cartesian mode: force and/or torque (N, N m, world frame), or position and/or "
          "orientation (a target pose; the part not given keeps the newest pose), or "
          "linear_velocity and/or angular_velocity (a target twist);\n"
          "  actuators: a flag per constraint actuator of the body, in file order (True holds "
          "what touches it).\n"
          "Raises ValueError for values that are not finite or too many, and "
          "afhub.CommandRefused when the physics refused an earlier command of this process.")
      .def("set_joint_positions", uniform(JointCommandType::kPosition), py::arg("values"),
           "Position targets for joints 0.. (rad or m): command(values, JointType.POSITION).")
      .def("set_joint_velocities", uniform(JointCommandType::kVelocity), py::arg("values"),
           "Velocity targets for joints 0.. (rad/s or m/s).")
      .def("set_joint_efforts", uniform(JointCommandType::kEffort), py::arg("values"),
           "Efforts for joints 0.. (N m or N).")
      .def("check_refused", &Body::check_refused,
           "Raises afhub.CommandRefused with the physics' reason when it refused a command of "
           "this process since the last check (command() checks too).")
      .def("__repr__", [](const Body& body) { return "<afhub.Body " + body.channel() + ">"; });
}

}  // namespace afhub::python
