// Reading `afhub bridge dds --config FILE` (see dds_bridge_config.hpp): every value is
// checked where it is written, and every problem names the file, line and column.
#include "afhub/bridges/dds_bridge_config.hpp"

#include <net/if.h>

#include <cmath>
#include <sstream>

#include "afhub/rt/cpu_wake_latency.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/limits.hpp"
#include "afhub/yaml/input_file.hpp"
#include "afhub/yaml/yaml_reader.hpp"

namespace afhub::bridges {
namespace {

using yaml::Reader;

const char* const kKeys =
    "domain, interface, export, mirror, accept-commands, insecure-accept-commands, bodies, "
    "devices, "
    "world, qos, rate, spin, cpu-wake-latency, rate-limits, max-command-age, max-mirrored, "
    "profile, ros2-prefix, security";

int microseconds(const Reader& reader, const YAML::Node& node, const std::string& key, int high) {
  const double value = reader.in_range(node, key, 0, high);
  if (value != std::floor(value)) reader.fail(node, "'" + key + "' is whole microseconds");
  return static_cast<int>(value);
}

std::string word(const Reader& reader, const YAML::Node& node, const std::string& key) {
  if (!node.IsScalar() || node.Scalar().empty()) reader.fail(node, "'" + key + "' must be a name");
  return node.Scalar();
}

// A glob or a list of globs.
std::vector<std::string> globs(const Reader& reader, const YAML::Node& node,
                               const std::string& key) {
  if (node.IsScalar()) return {word(reader, node, key)};
  if (!node.IsSequence())
    reader.fail(node, "'" + key + "' must be a glob or a list of globs, e.g. [\"ambf/env/*\"]");
  std::vector<std::string> out;
  for (const YAML::Node& item : node) out.push_back(word(reader, item, key));
  return out;
}

void read_rate_limits(const Reader& reader, const YAML::Node& node, DdsBridgeOptions& options) {
  if (!node.IsMap())
    reader.fail(node, "'rate-limits' must be a map, e.g. {bodies: 200, devices: 1000, world: 50}");
  for (const auto& entry : node) {
    const std::string key = entry.first.Scalar();
    const double rate = reader.in_range(entry.second, "rate-limits: " + key, 0.0, 100'000.0);
    if (key == "bodies")
      options.body_rate_hz = rate;
    else if (key == "devices")
      options.device_rate_hz = rate;
    else if (key == "world")
      options.world_rate_hz = rate;
    else
      reader.fail(entry.first, "unknown topic '" + key +
                                   "' in 'rate-limits'; the topics are bodies, devices and world "
                                   "(in Hz, 0 for no limit)");
  }
}

}  // namespace

DdsBridgeOptions read_dds_bridge_config(const std::string& path, const DdsBridgeOptions& defaults) {
  const YAML::Node root =
      yaml::parse(path, yaml::read_input_file(path, kMaxYamlFileBytes, "a bridge config file"));
  const Reader reader(path);
  DdsBridgeOptions options = defaults;
  if (root.IsNull()) return options;  // an empty file sets nothing
  if (!root.IsMap())
    reader.fail(root, "a bridge config is a map of settings: " + std::string(kKeys));
  for (const auto& entry : root) {
    const std::string key = entry.first.Scalar();
    const YAML::Node& value = entry.second;
    if (key == "domain") {
      const double domain = reader.in_range(value, key, 0, 232);
      if (std::floor(domain) != domain)
        reader.fail(value, "'domain' must be a whole number from 0 to 232");
      options.domain = static_cast<std::uint32_t>(domain);
    } else if (key == "interface") {
      options.interface = word(reader, value, key);
      try {
        check_interface_name(options.interface);
      } catch (const Error& error) {
        reader.fail(value, error.what());
      }
    } else if (key == "export") {
      options.export_bodies = reader.flag(value, key);
    } else if (key == "mirror") {
      options.mirror = reader.flag(value, key);
    } else if (key == "accept-commands") {
      options.accept_commands = reader.flag(value, key);
    } else if (key == "insecure-accept-commands") {
      options.insecure_accept_commands = reader.flag(value, key);
      options.accept_commands = options.accept_commands || options.insecure_accept_commands;
    } else if (key == "bodies") {
      options.body_globs = globs(reader, value, key);
      if (options.body_globs.empty()) reader.fail(value, "'bodies' needs at least one glob");
    } else if (key == "devices") {
      options.device_globs = globs(reader, value, key);
    } else if (key == "world") {
      options.world = reader.flag(value, key);
    } else if (key == "qos") {
      const std::string qos = value.IsScalar() ? value.Scalar() : "";
      if (qos != "best-effort" && qos != "reliable")
        reader.fail(value, "'qos' must be best-effort or reliable (states keep the last 1)");
      options.reliable = qos == "reliable";
    } else if (key == "rate") {
      options.rate_hz = reader.in_range(value, key, 1e-3, 100'000.0);
    } else if (key == "spin") {
      options.spin = reader.flag(value, key);
    } else if (key == "cpu-wake-latency") {
      options.cpu_wake_latency_us = microseconds(reader, value, key, kMaxCpuWakeLatencyUs);
    } else if (key == "rate-limits") {
      read_rate_limits(reader, value, options);
    } else if (key == "max-command-age") {
      options.max_command_age_s = reader.in_range(value, key, 1e-9, 10.0);
    } else if (key == "max-mirrored") {
      const double most = reader.in_range(value, key, 1, static_cast<double>(kMaxBodies));
      if (most != std::floor(most))
        reader.fail(value, "'max-mirrored' is a whole number of bodies");
      options.max_mirrored = static_cast<std::size_t>(most);
    } else if (key == "profile") {
      options.profile = word(reader, value, key);
      if (options.profile != "ros2") reader.fail(value, "'profile' must be ros2");
    } else if (key == "ros2-prefix") {
      options.ros2_prefix = word(reader, value, key);
    } else if (key == "security") {
      options.security_dir = word(reader, value, key);
    } else {
      reader.fail(entry.first, "unknown key '" + key + "'; the keys are " + kKeys +
                                   " (as the flags of `afhub bridge dds --help`)");
    }
  }
  return options;
}

namespace {

std::string quoted_list(const std::vector<std::string>& globs) {
  std::string out = "[";
  for (std::size_t i = 0; i < globs.size(); ++i)
    out += (i ? ", " : "") + std::string("\"") + globs[i] + "\"";
  return out + "]";
}

}  // namespace

std::string render_dds_bridge_config(const DdsBridgeOptions& options) {
  std::ostringstream out;
  const auto flag = [](bool value) { return value ? "true" : "false"; };
  out << "domain: " << options.domain << "\n";
  if (!options.interface.empty()) out << "interface: " << options.interface << "\n";
  out << "export: " << flag(options.export_bodies) << "\n"
      << "mirror: " << flag(options.mirror) << "\n"
      << "accept-commands: " << flag(options.accept_commands) << "\n";
  if (options.insecure_accept_commands) out << "insecure-accept-commands: true\n";
  out << "bodies: " << quoted_list(options.body_globs) << "\n"
      << "devices: " << quoted_list(options.device_globs) << "\n"
      << "world: " << flag(options.world) << "\n"
      << "qos: " << (options.reliable ? "reliable" : "best-effort") << "\n"
      << "rate: " << yaml::number_text(options.rate_hz) << "\n"
      << "spin: " << flag(options.spin) << "\n";
  if (options.cpu_wake_latency_us >= 0)
    out << "cpu-wake-latency: " << options.cpu_wake_latency_us << "\n";
  out << "rate-limits: {bodies: " << yaml::number_text(options.body_rate_hz)
      << ", devices: " << yaml::number_text(options.device_rate_hz)
      << ", world: " << yaml::number_text(options.world_rate_hz) << "}\n"
      << "max-command-age: " << yaml::number_text(options.max_command_age_s) << "\n"
      << "max-mirrored: " << options.max_mirrored << "\n";
  if (!options.profile.empty()) out << "profile: " << options.profile << "\n";
  if (!options.ros2_prefix.empty()) out << "ros2-prefix: " << options.ros2_prefix << "\n";
  if (!options.security_dir.empty()) out << "security: " << options.security_dir << "\n";
  return out.str();
}

void check_interface_name(const std::string& name) {
  if (name.empty()) return;
  if (name.size() >= IF_NAMESIZE)
    throw Error("interface '" + name + "' is longer than a network interface's name (" +
                std::to_string(IF_NAMESIZE - 1) + " characters); see `ip link`");
  for (const char c : name)
    if (c == '<' || c == '>' || c == '&' || c == '"' || c == '\'' || c == '/' || c == ' ' ||
        c == ',')
      throw Error("interface '" + name +
                  "' is not a network interface's name; see `ip link` for this machine's");
}

namespace {

// `text` without its elements <tag>...</tag>.
std::string without_element(std::string text, const std::string& tag) {
  const std::string open = "<" + tag + ">", close = "</" + tag + ">";
  for (std::size_t start = text.find(open); start != std::string::npos; start = text.find(open)) {
    const std::size_t end = text.find(close, start);
    if (end == std::string::npos) break;
    text.erase(start, end + close.size() - start);
  }
  return text;
}

}  // namespace

std::string cyclone_config_with_interface(const std::string& uri, const std::string& name) {
  // Cyclone adds up the interfaces of every part, and refuses one given twice: the
  // flag's interface replaces those written inline in the URI.
  std::string config;
  if (!uri.empty())
    config = without_element(without_element(uri, "Interfaces"), "NetworkInterfaceAddress") + ",";
  return config + "<General><Interfaces><NetworkInterface name=\"" + name +
         "\"/></Interfaces></General>";
}

std::string interface_config(const std::string& name) {
  if (if_nametoindex(name.c_str()) == 0)
    throw Error("--interface " + name +
                ": this machine has no such network interface; see `ip link`");
  const char* uri = std::getenv("CYCLONEDDS_URI");
  return cyclone_config_with_interface(uri ? uri : "", name);
}

}  // namespace afhub::bridges
