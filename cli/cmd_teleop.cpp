// `afhub teleop INPUT_DEVICES.yaml [-d 0,1] [--device NAME ...]`: AMBF's input device
// file, each selected device bound to the root body of its simulated multibody (see
// controllers/teleop/). The multibody's description is read here to find that body,
// its gains and its gripper joints; the physics (`afhub run`) simulates it.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <memory>

#include "afhub/physics/adf_loader.hpp"
#include "afhub/rt/percentile.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/teleop/input_devices_reader.hpp"
#include "afhub/teleop/teleop_process.hpp"
#include "commands.hpp"
#include "connection_options.hpp"
#include "count_option.hpp"
#include "loop_options.hpp"

namespace afhub::cli {
namespace {

struct TeleopCliOptions {
  std::string file;
  std::string selection;
  std::vector<std::string> devices;
  LoopRateOptions pacing;
  PhaseOptions phase;
  double wait_s = 10.0;
  double stale_ms = 50.0;
  std::uint64_t latency_samples = 0;
  std::string feedback = "proxy";
};

teleop::FeedbackSource feedback_source(const std::string& name) {
  if (name == "proxy") return teleop::FeedbackSource::kProxy;
  if (name == "contact") return teleop::FeedbackSource::kContact;
  if (name == "both") return teleop::FeedbackSource::kBoth;
  throw Error("--feedback: no feedback '" + name + "'; give proxy, contact or both");
}

// The driver name a hardware name maps to when no --device is given: lower case,
// every run of other characters than letters and digits one '_' ("Falcon" -> "falcon",
// "PHANTOM Omni" -> "phantom_omni").
std::string driver_name_of(const std::string& hardware_name) {
  std::string name;
  for (char c : hardware_name) {
    if (std::isalnum(static_cast<unsigned char>(c)))
      name += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    else if (!name.empty() && name.back() != '_')
      name += '_';
  }
  while (!name.empty() && name.back() == '_') name.pop_back();
  return name;
}

std::string quoted(const std::string& path) {
  return path.find_first_of(" '\"") == std::string::npos ? path : "'" + path + "'";
}

// The body the device drives: "root link" (a body's name, "BODY name", its qualified
// identifier or its channel) or else the first body that is no joint's child.
std::size_t root_body(const physics::Model& model, const teleop::InputDeviceSpec& spec) {
  if (!spec.root_link.empty()) {
    for (std::size_t b = 0; b < model.bodies.size(); ++b) {
      const physics::BodySpec& body = model.bodies[b];
      if (spec.root_link == body.name || spec.root_link == body.identifier ||
          spec.root_link == body.qualified_identifier || spec.root_link == body.channel ||
          spec.root_link == "/" + body.channel)
        return b;
    }
    std::string names;
    for (const physics::BodySpec& body : model.bodies) names += " '" + body.name + "'";
    throw Error(spec.where + ": error: root link '" + spec.root_link + "' is no body of " +
                spec.simulated_multibody + "; its bodies are" + names);
  }
  std::vector<bool> is_child(model.bodies.size(), false);
  for (const physics::JointSpec& joint : model.joints)
    if (joint.child >= 0) is_child[static_cast<std::size_t>(joint.child)] = true;
  for (std::size_t b = 0; b < model.bodies.size(); ++b)
    if (!is_child[b]) return b;
  throw Error(spec.simulated_multibody_where + ": error: " + spec.simulated_multibody +
              " has no root body (every body is a joint's child): give a \"root link\"");
}

teleop::TeleopBinding bind_device(const teleop::InputDeviceSpec& spec,
                                  const std::string& device_name) {
  device_channel_name(device_name);  // a bad name fails here, naming it
  const physics::Model model = physics::load_adf_files({spec.simulated_multibody});
  const std::size_t root = root_body(model, spec);
  const physics::BodySpec& body = model.bodies[root];
  teleop::TeleopBinding binding;
  binding.spec = spec;
  binding.device_name = device_name;
  binding.body = body.channel;
  // Teleop drives the body with a force: a file's force gains are taken; a velocity
  // controller's gains are no force gains, and AMBF's attribute defaults stand instead.
  const auto force_gains = [](const physics::Pid& pid, physics::ControllerOutput output) {
    return output == physics::ControllerOutput::kForce ? teleop::Gains{pid.p, pid.d}
                                                       : teleop::Gains{10.0, 1.0};
  };
  binding.body_gains.linear = force_gains(body.linear_controller, body.linear_output);
  binding.body_gains.angular = force_gains(body.angular_controller, body.angular_output);
  for (int j : model.descendant_joints[root]) {
    const physics::JointSpec& joint = model.joints[static_cast<std::size_t>(j)];
    binding.gripper_joints.push_back(
        {joint.limit_low.value_or(0.0), joint.limit_high.value_or(0.0)});
    // Every body below the root, once (a closed loop reaches one by two joints).
    if (joint.child < 0 || joint.child == static_cast<int>(root)) continue;
    const std::string& child = model.bodies[static_cast<std::size_t>(joint.child)].channel;
    if (std::find(binding.subtree_bodies.begin(), binding.subtree_bodies.end(), child) ==
        binding.subtree_bodies.end())
      binding.subtree_bodies.push_back(child);
  }
  for (const physics::ActuatorSpec& actuator : model.actuators)
    if (actuator.parent == static_cast<int>(root)) ++binding.actuator_count;
  // The physics bounds a body's force at 100 g times the mass it carries, and its
  // torque at that force times at least 1 m (physics/src/sim_bounds.cpp); a command
  // past them is refused whole. The whole multibody's mass stands for the root's.
  double mass_kg = 0.0;
  for (const physics::BodySpec& each : model.bodies) mass_kg += each.mass_kg;
  binding.body_limit.force_n = 0.99 * std::max(1.0, mass_kg) * 100.0 * 9.81;
  binding.body_limit.torque_nm = binding.body_limit.force_n;
  binding.load_hint = "the physics simulates it: start it with `afhub run " +
                      quoted(spec.simulated_multibody) + "`";
  return binding;
}

teleop::TeleopOptions teleop_options(const TeleopCliOptions& options) {
  if (!(options.stale_ms > 0.0 && options.stale_ms <= 60'000.0))
    throw Error("--stale takes milliseconds from 0 (excluded) to 60000");
  teleop::TeleopOptions teleop;
  set_loop_rate_options(options.pacing, teleop.loop);  // before the file is read
  const teleop::FeedbackSource feedback = feedback_source(options.feedback);
  const teleop::InputDevicesFile file = teleop::read_input_devices(options.file);
  for (const std::string& warning : file.warnings) std::fprintf(stderr, "%s\n", warning.c_str());
  const std::vector<teleop::InputDeviceSpec> selected =
      teleop::select_devices(file, options.selection);
  if (!options.devices.empty() && options.devices.size() != selected.size())
    throw Error("--device names " + std::to_string(options.devices.size()) + " device(s) but " +
                std::to_string(selected.size()) +
                " are selected: give one --device NAME per selected device, in the order of -d");
  for (std::size_t i = 0; i < selected.size(); ++i) {
    teleop.bindings.push_back(
        bind_device(selected[i], options.devices.empty() ? driver_name_of(selected[i].hardware_name)
                                                         : options.devices[i]));
    teleop.bindings.back().feedback = feedback;
  }
  teleop.wait_s = options.wait_s;
  teleop.stale_ns = std::llround(options.stale_ms * 1e6);
  teleop.latency_samples = options.latency_samples;
  teleop.after_step_ns = after_step_ns(options.phase, teleop.loop.period_ns);
  return teleop;
}

void print_latency(const char* what, std::vector<std::int64_t>& samples) {
  std::sort(samples.begin(), samples.end());
  const auto us = [&](double q) {
    return static_cast<double>(percentile_of_sorted<std::int64_t>(samples, q)) * 1e-3;
  };
  std::printf("%s: %zu samples, p50 %.1f us, p99 %.1f us, max %.1f us\n", what, samples.size(),
              us(0.5), us(0.99), us(1.0));
}

}  // namespace

void register_teleop(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<TeleopCliOptions>();
  auto* teleop = app.add_subcommand(
      "teleop",
      "Teleoperation with force feedback, from AMBF's input device file: each selected "
      "device's driver (device/<name>, `afhub device run ...`) moves the root body of its "
      "\"simulated multibody\" through a Cartesian PD wrench, and gets the haptic gain times "
      "the body's lag behind the device's proxy as force (clutch, gripper and mode buttons "
      "as AMBF maps them), or with --feedback contact the multibody's contact force. The physics "
      "simulates the multibody: start it with `afhub run "
      "<the simulated multibody file>` (it waits for it, printing that command). Device "
      "channels: by default the \"hardware name\" in lower case, other characters as '_' "
      "(Falcon -> device/falcon, PHANTOM Omni -> device/phantom_omni); --device NAME "
      "overrides it, one per selected device.");
  teleop->add_option("file", options->file, "AMBF input device file (input_devices.yaml)")
      ->required();
  teleop->add_option("-d,--devices", options->selection,
                     "Devices to use, by index in the file's \"input devices\" list: 0,1 "
                     "(default: all)");
  teleop->add_option("--device", options->devices,
                     "The driver (its --name) of each selected device, in the order of -d; "
                     "repeat it, e.g. --device virtual --device falcon2");
  add_loop_rate_options(teleop, options->pacing);
  add_phase_options(teleop, options->phase, "body command");
  add_wait_option(teleop, options->wait_s, "each device and body");
  teleop->add_option("--stale", options->stale_ms,
                     "A device with no new sample for this many ms (its driver stopped) "
                     "releases its body: held where it is, no force, until samples come back; "
                     "a body with no new state for this long (its physics stopped or died) "
                     "gets no force on the device until states come back (default 50)");
  teleop->add_option(
      "--feedback", options->feedback,
      "What the device's force renders: proxy (default, as AMBF: the haptic gain times the "
      "body's lag behind the device's proxy), contact (the force the contacts of the root body "
      "and every body below it push the multibody with, from the physics' contact wrenches, "
      "taken at the root, times haptic gain / the linear controller gain "
      "P, so that a steady press feels as with proxy; nothing while the body touches "
      "nothing), or both (their sum). The torque alike with the angular gains. Either way "
      "through the file's deadband, max force and max jerk, in the device's frame");
  add_count_option(teleop, "--latency", options->latency_samples,
                   "Record this many latencies (device sample -> body command, device sample "
                   "-> the device force answering it) and print p50/p99/max at the end");
  teleop->callback([&selected, options] {
    selected = [options] {
      const teleop::TeleopOptions run = teleop_options(*options);
      teleop::TeleopLatency latency;
      const int code = teleop::run_teleop(run, options->latency_samples > 0 ? &latency : nullptr);
      if (options->latency_samples > 0) {
        print_latency("device sample -> body command", latency.to_body_command);
        print_latency("device sample -> device force", latency.to_device_force);
      }
      return code;
    };
  });
}

}  // namespace afhub::cli
