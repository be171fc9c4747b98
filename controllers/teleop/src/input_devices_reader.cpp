// Reading input_devices.yaml: every value is checked where it is written, and every
// problem names its file, line and column (see input_devices_reader.hpp).
#include "afhub/teleop/input_devices_reader.hpp"

#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <unordered_map>

#include "afhub/shm_layout/error.hpp"

namespace afhub::teleop {
namespace {

namespace fs = std::filesystem;

// An input device file is a few kilobytes; this refuses a wrong file named by mistake.
constexpr std::uintmax_t kMaxFileBytes = 16u << 20;
// No gain, scale or force of a device comes near this; it keeps the arithmetic finite.
constexpr double kMaxMagnitude = 1e9;
constexpr double kMaxLengthM = 1e5;
// DeviceState::buttons has 32 bits.
constexpr int kMaxButton = 31;

std::string text_of(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

std::string read_text(const std::string& path) {
  std::error_code error;
  const fs::file_status status = fs::status(path, error);
  if (error || !fs::exists(status))
    throw Error(path + ": error: no such file; expected an input device file (input_devices.yaml)");
  if (fs::is_directory(status))
    throw Error(path + ": error: this is a directory; expected an input device file");
  if (!fs::is_regular_file(status))
    throw Error(path + ": error: this is not a regular file; expected an input device file");
  const std::uintmax_t size = fs::file_size(path, error);
  if (!error && size > kMaxFileBytes)
    throw Error(path + ": error: the file is " + std::to_string(size >> 20) +
                " MB, larger than any input device file; is it the right file?");
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw Error(path + ": error: cannot read it: " + std::strerror(errno) +
                "; check that you may read this file");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

const char* kind_of(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Map:
      return "a map";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Scalar:
      return "a value";
    default:
      return "nothing";
  }
}

// Reads the nodes of one file, with their locations.
class Reader {
 public:
  Reader(std::string path, std::vector<std::string>& warnings)
      : path_(std::move(path)), warnings_(warnings) {}

  std::string at(const YAML::Node& node) const {
    const YAML::Mark mark = node.Mark();
    return path_ + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
  }

  [[noreturn]] void fail(const YAML::Node& node, const std::string& what) const {
    throw Error(at(node) + ": error: " + what);
  }

  void warn(const YAML::Node& node, const std::string& what) const {
    warnings_.push_back(at(node) + ": warning: " + what);
  }

  void warn_unknown_keys(const YAML::Node& map, const std::set<std::string>& known,
                         const std::string& owner) const {
    for (const auto& entry : map) {
      const std::string key = entry.first.Scalar();
      if (!known.count(key))
        warn(entry.first, "unknown key '" + key + "' in " + owner + " is ignored");
    }
  }

  double number(const YAML::Node& node, const std::string& what) const {
    if (!node.IsScalar()) fail(node, "'" + what + "' must be a number, not " + kind_of(node));
    double value = 0.0;
    if (!YAML::convert<double>::decode(node, value))
      fail(node, "'" + what + "' must be a number, got '" + node.Scalar() + "'");
    if (!std::isfinite(value))
      fail(node, "'" + what + "' must be finite, got '" + node.Scalar() + "'");
    if (std::abs(value) > kMaxMagnitude)
      fail(node, "'" + what + "' is " + node.Scalar() + ", beyond any physical value (at most " +
                     text_of(kMaxMagnitude) + " in magnitude)");
    return value;
  }

  double non_negative(const YAML::Node& node, const std::string& what) const {
    const double value = number(node, what);
    if (value < 0.0) fail(node, "'" + what + "' must not be negative, got " + node.Scalar());
    return value;
  }

  double positive(const YAML::Node& node, const std::string& what) const {
    const double value = number(node, what);
    if (value <= 0.0) fail(node, "'" + what + "' must be greater than 0, got " + node.Scalar());
    return value;
  }

  int button(const YAML::Node& node, const std::string& what) const {
    int value = 0;
    if (!node.IsScalar() || !YAML::convert<int>::decode(node, value))
      fail(node, "'" + what + "' must be a button index (an integer, -1 for none), got " +
                     (node.IsScalar() ? "'" + node.Scalar() + "'" : std::string(kind_of(node))));
    if (value < -1 || value > kMaxButton)
      fail(node, "'" + what + "' is " + node.Scalar() + "; a button index is 0 to " +
                     std::to_string(kMaxButton) + ", or -1 for none");
    return value;
  }

  bool flag(const YAML::Node& node, const std::string& what) const {
    bool value = false;
    if (!node.IsScalar() || !YAML::convert<bool>::decode(node, value))
      fail(node, "'" + what + "' must be true or false");
    return value;
  }

  std::string text(const YAML::Node& node, const std::string& what) const {
    if (!node.IsScalar()) fail(node, "'" + what + "' must be text, not " + kind_of(node));
    return node.Scalar();
  }

  void require_map(const YAML::Node& node, const std::string& what,
                   const std::string& example) const {
    if (!node.IsMap())
      fail(node, "'" + what + "' must be a map such as " + example + ", not " + kind_of(node));
  }

  // {a, b, c} of numbers, every component required.
  Vec3 vec3(const YAML::Node& node, const std::string& what, const char* a, const char* b,
            const char* c, double bound) const {
    require_map(node, what, std::string("{") + a + ": 0, " + b + ": 0, " + c + ": 0}");
    warn_unknown_keys(node, {a, b, c}, "'" + what + "'");
    Vec3 out;
    double* slots[3] = {&out.x, &out.y, &out.z};
    const char* keys[3] = {a, b, c};
    for (int i = 0; i < 3; ++i) {
      const YAML::Node component = node[keys[i]];
      if (!component) fail(node, "'" + what + "' is missing '" + keys[i] + "'");
      *slots[i] = number(component, what + "." + keys[i]);
      if (std::abs(*slots[i]) > bound)
        fail(component, "'" + what + "." + keys[i] + "' is " + component.Scalar() +
                            ", beyond the bound of " + text_of(bound));
    }
    return out;
  }

 private:
  std::string path_;
  std::vector<std::string>& warnings_;
};

// A map's entries by key; a key written twice is refused (which one is meant is a guess).
class MapIndex {
 public:
  MapIndex(const Reader& reader, const YAML::Node& map) {
    for (const auto& entry : map) {
      const YAML::Node& key = entry.first;
      if (!key.IsScalar()) continue;
      auto [found, added] = entries_.try_emplace(key.Scalar(), Entry{key, entry.second});
      if (!added)
        reader.fail(key, "'" + key.Scalar() + "' is written twice in this map (first at " +
                             reader.at(found->second.key) + "); keep one");
    }
  }
  const YAML::Node* find(const std::string& key) const {
    auto found = entries_.find(key);
    return found == entries_.end() ? nullptr : &found->second.value;
  }

 private:
  struct Entry {
    YAML::Node key, value;
  };
  std::unordered_map<std::string, Entry> entries_;
};

YAML::Node parse(const std::string& path) {
  const std::string text = read_text(path);
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& error) {
    throw Error(path + ":" + std::to_string(error.mark.line + 1) + ":" +
                std::to_string(error.mark.column + 1) + ": error: YAML syntax: " + error.msg);
  } catch (const YAML::Exception& error) {
    throw Error(path + ": error: YAML: " + error.msg);
  }
  if (root.IsNull())
    throw Error(path +
                ":1:1: error: the file is empty; expected an input device file with "
                "an 'input devices' list");
  if (!root.IsMap())
    throw Error(path +
                ":1:1: error: expected an input device file (a map with an 'input "
                "devices' list), not " +
                kind_of(root));
  return root;
}

Gains read_gains(const Reader& reader, const YAML::Node& node, const std::string& what) {
  reader.require_map(node, what, "{P: 100, D: 5}");
  reader.warn_unknown_keys(node, {"P", "D"}, "'" + what + "'");
  Gains gains;
  if (const YAML::Node p = node["P"]) gains.p = reader.non_negative(p, what + ".P");
  if (const YAML::Node d = node["D"]) gains.d = reader.non_negative(d, what + ".D");
  return gains;
}

CartesianGains read_controller_gain(const Reader& reader, const YAML::Node& node) {
  reader.require_map(node, "controller gain", "{linear: {P: 100, D: 5}, angular: {P: 10, D: 1}}");
  reader.warn_unknown_keys(node, {"linear", "angular"}, "'controller gain'");
  CartesianGains gains;
  if (const YAML::Node linear = node["linear"])
    gains.linear = read_gains(reader, linear, "controller gain.linear");
  if (const YAML::Node angular = node["angular"])
    gains.angular = read_gains(reader, angular, "controller gain.angular");
  return gains;
}

void read_haptic_gain(const Reader& reader, const YAML::Node& node, InputDeviceSpec& spec) {
  reader.require_map(node, "haptic gain", "{linear: 10.0, angular: 0.0}");
  reader.warn_unknown_keys(node, {"linear", "angular"}, "'haptic gain'");
  if (const YAML::Node linear = node["linear"])
    spec.haptic_gain_linear = reader.non_negative(linear, "haptic gain.linear");
  if (const YAML::Node angular = node["angular"])
    spec.haptic_gain_angular = reader.non_negative(angular, "haptic gain.angular");
}

void read_location(const Reader& reader, const YAML::Node& node, InputDeviceSpec& spec) {
  reader.require_map(node, "location",
                     "{position: {x: 0, y: 0, z: 0}, orientation: {r: 0, p: 0, y: 0}}");
  reader.warn_unknown_keys(node, {"position", "orientation"}, "'location'");
  if (const YAML::Node position = node["position"])
    spec.location.position_m =
        reader.vec3(position, "location.position", "x", "y", "z", kMaxLengthM);
  if (const YAML::Node orientation = node["orientation"])
    spec.location.rpy_rad =
        reader.vec3(orientation, "location.orientation", "r", "p", "y", kMaxMagnitude);
  spec.location_given = true;
}

void read_buttons(const Reader& reader, const YAML::Node& node, ButtonMapping& buttons) {
  reader.require_map(node, "button mapping", "{a1: 0, a2: 1, g1: -1, next mode: 2, prev mode: 3}");
  reader.warn_unknown_keys(node, {"a1", "a2", "g1", "next mode", "prev mode"}, "'button mapping'");
  const std::pair<const char*, int*> keys[] = {{"a1", &buttons.clutch},
                                               {"a2", &buttons.camera},
                                               {"g1", &buttons.gripper},
                                               {"next mode", &buttons.next_mode},
                                               {"prev mode", &buttons.prev_mode}};
  for (const auto& [key, slot] : keys)
    if (const YAML::Node value = node[key])
      *slot = reader.button(value, std::string("button mapping.") + key);
}

std::vector<std::string> read_cameras(const Reader& reader, const YAML::Node& node) {
  if (!node.IsSequence())
    reader.fail(node, "'pair cameras' must be a list of camera names, e.g. [camera1], not " +
                          std::string(kind_of(node)));
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
                           kind_of(block));
  MapIndex index(reader, block);  // refuses a key written twice
  reader.warn_unknown_keys(block, kDeviceKeys, "the device '" + identifier + "'");
  InputDeviceSpec spec;
  spec.identifier = identifier;
  spec.where = reader.at(block);

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
        reader.vec3(*node, "orientation offset", "r", "p", "y", kMaxMagnitude);
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
    spec.simulated_multibody_where = reader.at(*node);
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
  const YAML::Node root = parse(path);
  const Reader reader(path, file.warnings);
  const MapIndex index(reader, root);
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
