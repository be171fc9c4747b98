// Reading input_devices.yaml: every value is checked where it is written, and every
// problem names its file, line and column (see input_devices_reader.hpp).
#include "afhub/teleop/input_devices_reader.hpp"

#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>

#include "afhub/shm_layout/error.hpp"
#include "afhub/yaml/yaml_reader.hpp"

namespace afhub::teleop {
namespace {

namespace fs = std::filesystem;
using yaml::Reader;

const char* const kWhat =
    "an input device file (input_devices.yaml: a map with an 'input devices' list)";
constexpr double kMaxLengthM = 1e5;
// DeviceState::buttons has 32 bits.
constexpr int kMaxButton = 31;

int button(const Reader& reader, const YAML::Node& node, const std::string& what) {
  int value = 0;
  if (!node.IsScalar() || !YAML::convert<int>::decode(node, value))
    reader.fail(
        node, "'" + what + "' must be a button index (an integer, -1 for none), got " +
                  (node.IsScalar() ? "'" + node.Scalar() + "'" : std::string(yaml::kind_of(node))));
  if (value < -1 || value > kMaxButton)
    reader.fail(node, "'" + what + "' is " + node.Scalar() + "; a button index is 0 to " +
                          std::to_string(kMaxButton) + ", or -1 for none");
  return value;
}

// {a, b, c} of numbers, every component required.
Vec3 vec3(const Reader& reader, const YAML::Node& node, const std::string& what, const char* a,
          const char* b, const char* c, double bound) {
  reader.require_map(node, what, std::string("{") + a + ": 0, " + b + ": 0, " + c + ": 0}");
  reader.check_keys(node, {a, b, c}, "'" + what + "'");
  Vec3 out;
  double* slots[3] = {&out.x, &out.y, &out.z};
  const char* keys[3] = {a, b, c};
  for (int i = 0; i < 3; ++i) {
    const YAML::Node component = node[keys[i]];
    if (!component) reader.fail(node, "'" + what + "' is missing '" + keys[i] + "'");
    *slots[i] = reader.number(component, what + "." + keys[i]);
    if (std::abs(*slots[i]) > bound)
      reader.fail(component, "'" + what + "." + keys[i] + "' is " + component.Scalar() +
                                 ", beyond the bound of " + yaml::number_text(bound));
  }
  return out;
}

Gains read_gains(const Reader& reader, const YAML::Node& node, const std::string& what) {
  reader.require_map(node, what, "{P: 100, D: 5}");
  reader.check_keys(node, {"P", "D"}, "'" + what + "'");
  Gains gains;
  if (const YAML::Node p = node["P"]) gains.p = reader.non_negative(p, what + ".P");
  if (const YAML::Node d = node["D"]) gains.d = reader.non_negative(d, what + ".D");
  return gains;
}

CartesianGains read_controller_gain(const Reader& reader, const YAML::Node& node) {
  reader.require_map(node, "controller gain", "{linear: {P: 100, D: 5}, angular: {P: 10, D: 1}}");
  reader.check_keys(node, {"linear", "angular"}, "'controller gain'");
  CartesianGains gains;
  if (const YAML::Node linear = node["linear"])
    gains.linear = read_gains(reader, linear, "controller gain.linear");
  if (const YAML::Node angular = node["angular"])
    gains.angular = read_gains(reader, angular, "controller gain.angular");
  return gains;
}

void read_haptic_gain(const Reader& reader, const YAML::Node& node, InputDeviceSpec& spec) {
  reader.require_map(node, "haptic gain", "{linear: 10.0, angular: 0.0}");
  reader.check_keys(node, {"linear", "angular"}, "'haptic gain'");
  if (const YAML::Node linear = node["linear"])
    spec.haptic_gain_linear = reader.non_negative(linear, "haptic gain.linear");
  if (const YAML::Node angular = node["angular"])
    spec.haptic_gain_angular = reader.non_negative(angular, "haptic gain.angular");
}

void read_location(const Reader& reader, const YAML::Node& node, InputDeviceSpec& spec) {
  reader.require_map(node, "location",
                     "{position: {x: 0, y: 0, z: 0}, orientation: {r: 0, p: 0, y: 0}}");
  reader.check_keys(node, {"position", "orientation"}, "'location'");
  if (const YAML::Node position = node["position"])
    spec.location.position_m =
        vec3(reader, position, "location.position", "x", "y", "z", kMaxLengthM);
  if (const YAML::Node orientation = node["orientation"])
    spec.location.rpy_rad =
        vec3(reader, orientation, "location.orientation", "r", "p", "y", yaml::kMaxMagnitude);
  spec.location_given = true;
}

void read_buttons(const Reader& reader, const YAML::Node& node, ButtonMapping& buttons) {
  reader.require_map(node, "button mapping", "{a1: 0, a2: 1, g1: -1, next mode: 2, prev mode: 3}");
  reader.check_keys(node, {"a1", "a2", "g1", "next mode", "prev mode"}, "'button mapping'");
  const std::pair<const char*, int*> keys[] = {{"a1", &buttons.clutch},
                                               {"a2", &buttons.camera},
                                               {"g1", &buttons.gripper},
                                               {"next mode", &buttons.next_mode},
                                               {"prev mode", &buttons.prev_mode}};
  for (const auto& [key, slot] : keys)
    if (const YAML::Node value = node[key])
      *slot = button(reader, value, std::string("button mapping.") + key);
}

std::vector<std::string> read_cameras(const Reader& reader, const YAML::Node& node) {
  if (!node.IsSequence())
    reader.fail(node, "'pair cameras' must be a list of camera names, e.g. [camera1], not " +
                          std::string(yaml::kind_of(node)));
  std::vector<std::string> cameras;
  for (const auto& item : node) cameras.push_back(reader.text(item, "pair cameras entry"));
  return cameras;
}

const std::set<std::string> kDeviceKeys = {"hardware name",
                                           "haptic gain",
                                           "workspace scaling",
                                           "location",
                                           "controller gain",
                                           "deadband",
                                           "max force",
                                           "max jerk",
                                           "button mapping",
                                           "root link",
                                           "simulated multibody",
                                           "pair cameras",
                                           "orientation offset",
                                           "enable joint control",
                                           "visible",
                                           "visible size",
                                           "visible color"};

InputDeviceSpec read_device(const Reader& reader, const fs::path& folder,
                            const std::string& identifier, const YAML::Node& listed,
                            const YAML::Node& block) {
  if (!block.IsMap())
    reader.fail(block, "the device '" + identifier +
                           "' must be a map of keys such as "
                           "'hardware name', not " +
                           yaml::kind_of(block));
  yaml::MapIndex index(reader, block);  // refuses a key written twice
  reader.check_keys(block, kDeviceKeys, "the device '" + identifier + "'");
  InputDeviceSpec spec;
  spec.identifier = identifier;
  spec.where = reader.where(block);

  const YAML::Node* hardware = index.find("hardware name");
  if (!hardware)
    reader.fail(listed, "the device '" + identifier +
                            "' has no 'hardware name'; add it, e.g. 'hardware name: Falcon'");
  spec.hardware_name = reader.text(*hardware, "hardware name");
  if (spec.hardware_name.empty())
    reader.fail(*hardware, "'hardware name' is empty; name the device, e.g. 'Falcon'");

  if (const YAML::Node* node = index.find("haptic gain")) read_haptic_gain(reader, *node, spec);
  if (const YAML::Node* node = index.find("workspace scaling"))
    spec.workspace_scale = reader.positive(*node, "workspace scaling");
  if (const YAML::Node* node = index.find("location")) read_location(reader, *node, spec);
  if (const YAML::Node* node = index.find("orientation offset"))
    spec.orientation_offset_rpy =
        vec3(reader, *node, "orientation offset", "r", "p", "y", yaml::kMaxMagnitude);
  if (const YAML::Node* node = index.find("controller gain"))
    spec.controller_gain = read_controller_gain(reader, *node);
  if (const YAML::Node* node = index.find("deadband"))
    spec.deadband_n = reader.non_negative(*node, "deadband");
  if (const YAML::Node* node = index.find("max force"))
    spec.max_force_n = reader.positive(*node, "max force");
  if (const YAML::Node* node = index.find("max jerk"))
    spec.max_jerk_n_per_ms = reader.positive(*node, "max jerk");
  if (const YAML::Node* node = index.find("button mapping"))
    read_buttons(reader, *node, spec.buttons);
  if (const YAML::Node* node = index.find("root link"))
    spec.root_link = reader.text(*node, "root link");
  if (const YAML::Node* node = index.find("simulated multibody")) {
    const std::string given = reader.text(*node, "simulated multibody");
    if (given.empty())
      reader.fail(*node, "'simulated multibody' is empty; name an ADF file, or remove the key");
    spec.simulated_multibody = (folder / given).lexically_normal().string();
    spec.simulated_multibody_where = reader.where(*node);
  }
  if (const YAML::Node* node = index.find("enable joint control"))
    spec.enable_joint_control = reader.flag(*node, "enable joint control");
  if (const YAML::Node* node = index.find("pair cameras"))
    spec.pair_cameras = read_cameras(reader, *node);
  if (const YAML::Node* node = index.find("visible")) spec.visible = reader.flag(*node, "visible");
  if (const YAML::Node* node = index.find("visible size"))
    spec.visible_size_m = reader.non_negative(*node, "visible size");
  if (const YAML::Node* node = index.find("visible color")) reader.text(*node, "visible color");

  // AMBF needs one of the two to bind the device to a body.
  if (spec.simulated_multibody.empty() && spec.root_link.empty())
    reader.fail(listed, "the device '" + identifier +
                            "' has neither 'simulated multibody' nor 'root link'; give the "
                            "ADF file of the body it drives, or the name of a body to drive");
  return spec;
}

}  // namespace

InputDevicesFile read_input_devices(const std::string& path) {
  InputDevicesFile file;
  file.path = path;
  const YAML::Node root = yaml::load_map(path, kWhat);
  const Reader reader(path, &file.warnings);
  const yaml::MapIndex index(reader, root);
  const YAML::Node* list = index.find("input devices");
  if (!list)
    throw Error(path +
                ":1:1: error: no 'input devices' list; an input device file lists its "
                "devices, e.g. 'input devices: [Novint Falcon1]', each with its block");
  if (!list->IsSequence())
    reader.fail(*list, "'input devices' must be a list of device names, e.g. [Novint Falcon1]");
  const fs::path folder = fs::path(path).parent_path();
  std::set<std::string> seen;
  for (const auto& item : *list) {
    const std::string identifier = reader.text(item, "input devices entry");
    if (!seen.insert(identifier).second)
      reader.fail(item, "'" + identifier + "' is listed twice in 'input devices'; keep one");
    const YAML::Node* block = index.find(identifier);
    if (!block)
      reader.fail(item, "'" + identifier +
                            "' is listed in 'input devices' but the file has no top-level '" +
                            identifier + "' block; add the block or remove it from the list");
    file.devices.push_back(read_device(reader, folder, identifier, item, *block));
  }
  return file;
}

std::vector<InputDeviceSpec> select_devices(const InputDevicesFile& file,
                                            const std::string& selection) {
  std::string listing;
  for (std::size_t i = 0; i < file.devices.size(); ++i)
    listing += (i ? ", " : "") + std::to_string(i) + " '" + file.devices[i].identifier + "'";
  if (file.devices.empty()) listing = "none";

  std::vector<std::size_t> indices;
  if (selection.empty()) {
    for (std::size_t i = 0; i < file.devices.size(); ++i) indices.push_back(i);
  } else {
    std::stringstream parts(selection);
    std::string part;
    while (std::getline(parts, part, ',')) {
      std::size_t used = 0;
      long index = -1;
      try {
        index = std::stol(part, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != part.size() || part.empty() || index < 0)
        throw Error("-d " + selection + ": '" + part +
                    "' is not a device index; give indices into 'input devices' of " + file.path +
                    ", e.g. -d 0,1 (devices: " + listing + ")");
      if (static_cast<std::size_t>(index) >= file.devices.size())
        throw Error("-d " + selection + ": there is no device " + part + " in " + file.path +
                    " (devices: " + listing + ")");
      indices.push_back(static_cast<std::size_t>(index));
    }
    if (selection.back() == ',')
      throw Error("-d " + selection + ": ends with ','; give indices such as -d 0,1");
  }

  std::vector<InputDeviceSpec> chosen;
  for (std::size_t index : indices) {
    const InputDeviceSpec& spec = file.devices[index];
    for (const InputDeviceSpec& earlier : chosen)
      if (earlier.identifier == spec.identifier)
        throw Error("-d " + selection + ": device " + std::to_string(index) + " '" +
                    spec.identifier + "' is selected twice; select each device once");
    if (!spec.simulated_multibody.empty() && !fs::is_regular_file(spec.simulated_multibody))
      throw Error(spec.simulated_multibody_where + ": error: the simulated multibody of '" +
                  spec.identifier + "' is " + spec.simulated_multibody +
                  ", and there is no such file (the path is relative to the input device "
                  "file's folder)");
    chosen.push_back(spec);
  }
  return chosen;
}

}  // namespace afhub::teleop
