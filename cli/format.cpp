// Payload rendering and flag parsing (see format.hpp).
#include "format.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/json_writer.hpp"
#include "afhub/shm_layout/error.hpp"

namespace afhub::cli {
namespace {

void vec3(JsonWriter& json, const Vec3& v) {
  json.begin_array().value(v.x).value(v.y).value(v.z).end_array();
}

}  // namespace

std::string state_json(const BodyInfo& info, const BodyState& state) {
  JsonWriter json;
  const std::size_t joints = state.joint_count;
  json.begin_object();
  json.key("body").value(name_of(info.channel));
  json.key("sequence").value(static_cast<unsigned long long>(state.header.sequence));
  json.key("sim_step").value(static_cast<unsigned long long>(state.header.sim_step));
  json.key("sim_time_s").value(state.header.sim_time_s);
  json.key("publish_stamp_ns").value(static_cast<long long>(state.header.publish_stamp_ns));
  json.key("publisher_pid").value(static_cast<long long>(state.header.publisher_pid));
  json.key("position_m");
  vec3(json, state.pose.position_m);
  const Quaternion& q = state.pose.orientation;
  json.key("orientation_xyzw")
      .begin_array()
      .value(q.x)
      .value(q.y)
      .value(q.z)
      .value(q.w)
      .end_array();
  json.key("linear_velocity_mps");
  vec3(json, state.twist.linear_mps);
  json.key("angular_velocity_radps");
  vec3(json, state.twist.angular_radps);
  json.key("force_n");
  vec3(json, state.wrench.force_n);
  json.key("torque_nm");
  vec3(json, state.wrench.torque_nm);
  json.key("mass_kg").value(state.mass_kg);
  json.key("principal_inertia_kgm2");
  vec3(json, state.principal_inertia_kgm2);
  json.key("joint_names").begin_array();
  for (std::size_t i = 0; i < joints && i < info.joint_count; ++i)
    json.value(name_of(info.joint_names[i]));
  json.end_array();
  json.key("joint_positions").numbers(state.joint_positions, joints);
  json.key("joint_velocities").numbers(state.joint_velocities, joints);
  json.key("joint_efforts").numbers(state.joint_efforts, joints);
  json.end_object();
  return json.str();
}

std::string state_text(const BodyInfo& info, const BodyState& state) {
  char line[256];
  const Vec3& p = state.pose.position_m;
  std::snprintf(line, sizeof line, "%s step %llu t=%.3fs pos [%.4f %.4f %.4f]",
                std::string(name_of(info.channel)).c_str(),
                static_cast<unsigned long long>(state.header.sim_step), state.header.sim_time_s,
                p.x, p.y, p.z);
  std::string out = line;
  if (state.joint_count > 0) {
    out += " joints [";
    for (std::uint32_t i = 0; i < state.joint_count; ++i) {
      std::snprintf(line, sizeof line, "%s%.4f", i ? " " : "", state.joint_positions[i]);
      out += line;
    }
    out += "]";
  }
  return out;
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
    char* parsed_end = nullptr;
    errno = 0;
    double value = std::strtod(item.c_str(), &parsed_end);
    if (item.empty() || *parsed_end != '\0' || errno == ERANGE || !std::isfinite(value))
      throw Error(std::string(flag) + ": '" + item +
                  "' is not a finite number; give comma-separated numbers, e.g. " +
                  std::string(flag) + " 0.1,0.2");
    values.push_back(value);
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

}  // namespace afhub::cli
