// Payload rendering and flag parsing (see format.hpp).
#include "format.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/json_writer.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/force_gate_name.hpp"
#include "afhub/yaml/number_text.hpp"

namespace afhub::cli {
namespace {

void vec3(JsonWriter& json, const Vec3& v) {
  json.begin_array().value(v.x).value(v.y).value(v.z).end_array();
}

void quaternion(JsonWriter& json, const Quaternion& q) {
  json.begin_array().value(q.x).value(q.y).value(q.z).value(q.w).end_array();
}

}  // namespace

StateFields parse_state_fields(const std::string& text) {
  StateFields fields{false, false, false, false, false, false, false, false};
  const std::vector<std::string> names = split_commas(text);
  if (names.empty())
    throw Error(std::string("--fields takes a comma-separated list of: ") + kStateFieldNames);
  for (const std::string& name : names) {
    if (name == "pose") {
      fields.pose = true;
    } else if (name == "twist") {
      fields.twist = true;
    } else if (name == "wrench") {
      fields.wrench = true;
    } else if (name == "contact") {
      fields.contact = true;
    } else if (name == "joints") {
      fields.joints = true;
    } else if (name == "joint_velocities") {
      fields.joint_velocities = true;
    } else if (name == "joint_efforts") {
      fields.joint_efforts = true;
    } else if (name == "mass") {
      fields.mass = true;
    } else if (name == "all") {
      fields = StateFields{};
    } else {
      throw Error("--fields: no field '" + name + "'; the fields are " + kStateFieldNames);
    }
  }
  return fields;
}

StateFields default_text_fields() {
  StateFields fields;
  fields.wrench = fields.contact = fields.joint_velocities = fields.joint_efforts = fields.mass =
      false;
  return fields;
}

std::string state_json(const BodyEntry& entry, const BodyState& state, const StateFields& fields) {
  const BodyInfo& info = entry.info;
  JsonWriter json;
  const std::size_t joints = state.joint_count;
  json.begin_object();
  json.key("body").value(name_of(info.channel));
  json.key("sequence").value(static_cast<unsigned long long>(state.header.sequence));
  json.key("sim_step").value(static_cast<unsigned long long>(state.header.sim_step));
  json.key("sim_time_s").value(state.header.sim_time_s);
  json.key("publish_stamp_ns").value(static_cast<long long>(state.header.publish_stamp_ns));
  json.key("publisher_pid").value(static_cast<long long>(state.header.publisher_pid));
  json.key("command_answered_step").value(static_cast<long long>(state.command_answered_step));
  if (fields.pose) {
    json.key("position_m");
    vec3(json, state.pose.position_m);
    json.key("orientation_xyzw");
    quaternion(json, state.pose.orientation);
  }
  if (fields.twist) {
    json.key("linear_velocity_mps");
    vec3(json, state.twist.linear_mps);
    json.key("angular_velocity_radps");
    vec3(json, state.twist.angular_radps);
  }
  if (fields.wrench) {
    json.key("force_n");
    vec3(json, state.wrench.force_n);
    json.key("torque_nm");
    vec3(json, state.wrench.torque_nm);
  }
  if (fields.contact) {
    json.key("contact_force_n");
    vec3(json, state.contact_wrench.force_n);
    json.key("contact_torque_nm");
    vec3(json, state.contact_wrench.torque_nm);
    json.key("contact_count").value(static_cast<unsigned long long>(state.contact_count));
  }
  if (fields.mass) {
    json.key("mass_kg").value(state.mass_kg);
    json.key("principal_inertia_kgm2");
    vec3(json, state.principal_inertia_kgm2);
  }
  if (fields.joints || fields.joint_velocities || fields.joint_efforts) {
    json.key("joint_names").begin_array();
    for (std::size_t i = 0; i < joints && i < entry.joint_names.size(); ++i)
      json.value(entry.joint_names[i]);
    json.end_array();
  }
  auto joint_numbers = [&](const char* key, double JointSample::*field) {
    json.key(key).begin_array();
    for (std::size_t i = 0; i < joints; ++i) json.value(state.joints[i].*field);
    json.end_array();
  };
  if (fields.joints) joint_numbers("joint_positions", &JointSample::position);
  if (fields.joint_velocities) joint_numbers("joint_velocities", &JointSample::velocity);
  if (fields.joint_efforts) joint_numbers("joint_efforts", &JointSample::effort);
  json.end_object();
  return json.str();
}

namespace {

void append(std::string& out, const char* label, const double* values, std::size_t count) {
  char number[64];
  out += " ";
  out += label;
  out += " [";
  for (std::size_t i = 0; i < count; ++i) {
    std::snprintf(number, sizeof number, "%s%.4f", i ? " " : "", values[i]);
    out += number;
  }
  out += "]";
}

void append(std::string& out, const char* label, const BodyState& state, double JointSample::*field,
            std::size_t count) {
  char number[64];
  out += " ";
  out += label;
  out += " [";
  for (std::size_t i = 0; i < count; ++i) {
    std::snprintf(number, sizeof number, "%s%.4f", i ? " " : "", state.joints[i].*field);
    out += number;
  }
  out += "]";
}

}  // namespace

std::string state_text(const BodyEntry& entry, const BodyState& state, const StateFields& fields) {
  char line[256];
  std::snprintf(line, sizeof line, "%s step %llu t=%.3fs",
                std::string(name_of(entry.info.channel)).c_str(),
                static_cast<unsigned long long>(state.header.sim_step), state.header.sim_time_s);
  std::string out = line;
  const auto v3 = [](const Vec3& v) { return std::array<double, 3>{v.x, v.y, v.z}; };
  if (fields.pose) {
    const Quaternion& q = state.pose.orientation;
    const std::array<double, 4> quat{q.x, q.y, q.z, q.w};
    append(out, "pos", v3(state.pose.position_m).data(), 3);
    append(out, "quat_xyzw", quat.data(), 4);
  }
  if (fields.twist) {
    append(out, "lin_vel", v3(state.twist.linear_mps).data(), 3);
    append(out, "ang_vel", v3(state.twist.angular_radps).data(), 3);
  }
  if (fields.wrench) {
    append(out, "force", v3(state.wrench.force_n).data(), 3);
    append(out, "torque", v3(state.wrench.torque_nm).data(), 3);
  }
  if (fields.contact) {
    append(out, "contact_force", v3(state.contact_wrench.force_n).data(), 3);
    append(out, "contact_torque", v3(state.contact_wrench.torque_nm).data(), 3);
    out += " contacts " + std::to_string(state.contact_count);
  }
  if (fields.mass) {
    append(out, "mass", &state.mass_kg, 1);
    append(out, "inertia", v3(state.principal_inertia_kgm2).data(), 3);
  }
  const std::size_t joints = std::min<std::size_t>(state.joint_count, kMaxJointsPerBody);
  if (joints > 0) {
    if (fields.joints) append(out, "joints", state, &JointSample::position, joints);
    if (fields.joint_velocities) append(out, "joint_vel", state, &JointSample::velocity, joints);
    if (fields.joint_efforts) append(out, "joint_eff", state, &JointSample::effort, joints);
  }
  return out;
}

bool rate_measured(double rate_hz) {
  return std::isfinite(rate_hz) && rate_hz > 0.0;
}

std::string rate_text(double rate_hz) {
  if (!rate_measured(rate_hz)) return "-";
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", rate_hz);
  return text;
}

std::vector<double> parse_numbers(std::string_view text, std::string_view flag,
                                  std::size_t expected) {
  std::vector<double> values;
  std::string rest(text);
  std::size_t start = 0;
  while (start <= rest.size()) {
    std::size_t end = rest.find(',', start);
    if (end == std::string::npos) end = rest.size();
    std::string item = rest.substr(start, end - start);
    const std::optional<double> value = yaml::parse_finite(item);
    if (!value) {
      std::string example = "0.1";
      for (std::size_t i = 1; i < std::max<std::size_t>(expected, 2); ++i)
        example += ",0." + std::to_string(i + 1);
      throw Error(std::string(flag) + ": '" + item +
                  "' is not a finite number; give comma-separated numbers, e.g. " +
                  std::string(flag) + " " + example);
    }
    values.push_back(*value);
    start = end + 1;
  }
  if (expected != 0 && values.size() != expected)
    throw Error(std::string(flag) + " takes " + std::to_string(expected) + " numbers, got " +
                std::to_string(values.size()) + " ('" + rest + "')");
  return values;
}

std::vector<std::string> split_commas(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream stream(text);
  for (std::string item; std::getline(stream, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

std::string device_state_json(const BodyEntry& entry, const DeviceState& state) {
  JsonWriter json;
  json.begin_object();
  json.key("device").value(name_of(entry.info.channel));
  json.key("model").value(name_of(state.spec.model));
  json.key("sequence").value(static_cast<long long>(state.header.sequence));
  json.key("stamp_ns").value(static_cast<long long>(state.header.publish_stamp_ns));
  json.key("position");
  vec3(json, state.pose.position_m);
  json.key("orientation_xyzw");
  quaternion(json, state.pose.orientation);
  json.key("linear_velocity");
  vec3(json, state.velocity.linear_mps);
  json.key("angular_velocity");
  vec3(json, state.velocity.angular_radps);
  json.key("gripper_angle").value(state.gripper_angle_rad);
  json.key("buttons").value(static_cast<long long>(state.buttons));
  json.key("force_gate").value(force_gate_name(state.gate));
  json.key("applied_force");
  vec3(json, state.applied.force_n);
  json.key("applied_torque");
  vec3(json, state.applied.torque_nm);
  json.key("applied_gripper_force").value(state.applied_gripper_force_n);
  json.key("max_force").value(state.spec.max_force_n);
  json.end_object();
  return json.str();
}

std::string device_state_text(const BodyEntry& entry, const DeviceState& state) {
  char line[256];
  std::snprintf(line, sizeof line, "%s seq %llu buttons 0x%x gripper %.4f force %s",
                std::string(name_of(entry.info.channel)).c_str(),
                static_cast<unsigned long long>(state.header.sequence), state.buttons,
                state.gripper_angle_rad, force_gate_name(state.gate));
  std::string out = line;
  const auto v3 = [](const Vec3& v) { return std::array<double, 3>{v.x, v.y, v.z}; };
  append(out, "pos", v3(state.pose.position_m).data(), 3);
  append(out, "lin_vel", v3(state.velocity.linear_mps).data(), 3);
  append(out, "applied_force", v3(state.applied.force_n).data(), 3);
  return out;
}

}  // namespace afhub::cli
