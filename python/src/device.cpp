// afhub.Device: a haptic or input device's newest state and its force command, on the
// channels its driver process (`afhub device run`) publishes and reads.
#include <pybind11/stl.h>

#include <chrono>
#include <cmath>
#include <string>
#include <string_view>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_loss.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/shm_layout/device.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/force_gate_name.hpp"
#include "bindings.hpp"

namespace afhub::python {
namespace {

py::array vec3(const Vec3& v) {
  return py::array_t<double>(3, &v.x);
}

// The devices live now, for a name that matched none: the catalog's bodies were listed.
std::string live_devices() {
  CatalogReader catalog;
  catalog.wait(std::chrono::milliseconds(1000));
  const BodyList& list = catalog.latest();
  std::string names;
  for (std::uint32_t i = 0; i < list.body_count; ++i)
    if (list.bodies[i].kind == ChannelKind::kDevice)
      names += (names.empty() ? "" : ", ") + std::string(name_of(list.bodies[i].channel));
  return names.empty() ? "none (a driver: `afhub device run ...`)" : names;
}

BodyEntry device_entry(const std::string& name, double wait_s) {
  try {
    return wait_for_entry(name, wait_s, "device");
  } catch (const Error& error) {
    if (!std::string_view(error.what()).starts_with("no live body is named")) throw;
    throw Error("no live device is named '" + name + "'; live devices: " + live_devices() +
                " (wait_s waits for a driver started later)");
  }
}

class Device {
 public:
  Device(const std::string& name, double wait_s)
      : entry_([&] {
          BodyEntry entry = device_entry(name, wait_s);
          if (entry.info.kind != ChannelKind::kDevice)
            throw Error("'" + std::string(name_of(entry.info.channel)) +
                        "' is a body, not a device: open it with afhub.Body");
          return entry;
        }()),
        channel_(name_of(entry_.info.channel)),
        state_(body_state_channel(channel_)),
        command_(body_command_channel(channel_)) {}

  const std::string& channel() const { return channel_; }

  std::optional<py::dict> read(double wait_s) {
    require_hub();
    const std::int64_t give_up = deadline_after(wait_s, "wait_s");  // checked, waited or not
    const DeviceState* s = state_.latest();
    if (!s && wait_s > 0.0) {
      SignalWatch signals;
      {
        py::gil_scoped_release release;
        while (!(s = state_.latest()) && monotonic_ns() < give_up && !signals.pending())
          sleep_until_ns(monotonic_ns() + 1'000'000);
      }
      signals.raise_if_pending();
    }
    if (!s) return std::nullopt;
    py::dict out;
    out["stamp_ns"] = s->header.publish_stamp_ns;
    out["model"] = std::string(name_of(s->spec.model));
    out["serial"] = std::string(name_of(s->spec.serial));
    out["max_force_n"] = s->spec.max_force_n;
    out["button_count"] = s->spec.button_count;
    out["position"] = vec3(s->pose.position_m);
    out["orientation"] = py::array_t<double>(4, &s->pose.orientation.x);
    out["linear_velocity"] = vec3(s->velocity.linear_mps);
    out["angular_velocity"] = vec3(s->velocity.angular_radps);
    out["gripper_angle"] = s->gripper_angle_rad;
    py::list buttons;
    for (std::uint32_t i = 0; i < s->spec.button_count && i < 32; ++i)
      buttons.append((s->buttons >> i & 1U) != 0);
    out["buttons"] = buttons;
    out["gate"] = force_gate_name(s->gate);
    out["applied_force"] = vec3(s->applied.force_n);
    out["applied_torque"] = vec3(s->applied.torque_nm);
    out["applied_gripper_force"] = s->applied_gripper_force_n;
    return out;
  }

  void command(const py::object& force, const py::object& torque, double gripper_force,
               bool enable) {
    const Vec3 f = force.is_none() ? Vec3{} : to_vec3(force, "force");
    const Vec3 t = torque.is_none() ? Vec3{} : to_vec3(torque, "torque");
    if (!std::isfinite(gripper_force))
      throw py::value_error("gripper_force is not a finite number: nothing was sent");
    require_hub();
    DeviceCommand* command = command_.loan();
    if (!command) throw Error("shared memory is exhausted: the command was not sent");
    command->wrench.force_n = f;
    command->wrench.torque_nm = t;
    command->gripper_force_n = gripper_force;
    command->enable = enable;
    command_.publish(command);
  }

 private:
  BodyEntry entry_;
  std::string channel_;
  LatestReader<DeviceState> state_;
  Writer<DeviceCommand> command_;
};

}  // namespace

void register_device(py::module_& module) {
  py::class_<Device>(module, "Device",
                     "A haptic or input device driven by `afhub device run`. Device(name, "
                     "wait_s=0): 'device/virtual' or a unique suffix ('virtual').")
      .def(py::init<const std::string&, double>(), py::arg("name"), py::arg("wait_s") = 0.0)
      .def_property_readonly("channel", &Device::channel)
      .def("read", &Device::read, py::arg("wait_s") = 0.0,
           "The newest state as a dict (copies): stamp_ns, model, serial, max_force_n, "
           "button_count, position, orientation (x, y, z, w), linear_velocity, "
           "angular_velocity, gripper_angle, buttons, gate (why a force is applied or not), "
           "applied_force, applied_torque, applied_gripper_force; None before the first.")
      .def("command", &Device::command, py::kw_only(), py::arg("force") = py::none(),
           py::arg("torque") = py::none(), py::arg("gripper_force") = 0.0, py::arg("enable") = true,
           "The force (N) and torque (N m) in the device's frame and the gripper force; the "
           "driver clamps them to the device's limits, ramps them in, and drops them when "
           "commands stop for its timeout: send them every cycle.");
}

}  // namespace afhub::python
