// ADF proximity sensors (SENSOR blocks): the parent body, placement, range, and
// rays given as an array or spread parametrically over two angles.
#include <cmath>

#include "adf_blocks.hpp"
#include "afhub/shm_layout/limits.hpp"
#include "frames.hpp"

namespace afhub::physics::adf {
namespace {

const std::set<std::string> kSensorKeys = {
    "name",  "namespace",  "type",    "parent",       "location",          "range",
    "array", "parametric", "visible", "visible size", "publish frequency", "plugins"};

}  // namespace

SensorSpec read_sensor(const FileReader& file, const YAML::Node& block,
                       const std::string& identifier, PendingParent& pending) {
  SensorSpec sensor;
  read_block_head(file, block, identifier, kSensorKeys, "sensor", sensor);
  const YAML::Node type = file.require(block, "type", sensor.where);
  const std::string kind = lower(file.text(type, "type"));
  if (kind != "proximity" && kind != "resistance")
    fail(file.at(type), "unknown sensor type '" + type.Scalar() + "'; use Proximity or Resistance");
  read_parent(file, block, sensor.where, pending);
  if (YAML::Node location = block["location"])
    sensor.location = file.placement(location, "location");
  if (YAML::Node range = block["range"]) {
    positive(file, range, "range");
    sensor.range_m = file.length(range, "range");
  }
  if (YAML::Node array = block["array"]) {
    if (!array.IsSequence() || array.size() == 0)
      fail(file.at(array), "'array' must be a non-empty list of {offset, direction}");
    if (array.size() > kMaxSensorRaysPerBody)
      fail(file.at(array), "'array' has " + std::to_string(array.size()) +
                               " rays; a body's state carries at most " +
                               std::to_string(kMaxSensorRaysPerBody) + " (kMaxSensorRaysPerBody)");
    for (const auto& ray : array) {
      file.require_map(ray, "array entry", "{offset: {x, y, z}, direction: {x, y, z}}");
      Vec3 offset;
      if (ray["offset"]) offset = file.position(ray["offset"], "array.offset");
      sensor.rays.emplace_back(
          offset, file.axis(file.require(ray, "direction", file.at(ray)), "array.direction"));
    }
  } else if (YAML::Node parametric = block["parametric"]) {
    file.require_map(parametric, "parametric", "{resolution: 4, horizontal angle: 0.5, ...}");
    const YAML::Node resolution_node = file.require(parametric, "resolution", file.at(parametric));
    const double rays_per_side = positive(file, resolution_node, "parametric.resolution");
    // resolution^2 rays, and a body's state carries kMaxSensorRaysPerBody.
    if (rays_per_side != std::floor(rays_per_side) ||
        rays_per_side * rays_per_side > kMaxSensorRaysPerBody)
      fail(file.at(resolution_node),
           "'parametric.resolution' must be an integer whose square (the rays) is at most " +
               std::to_string(kMaxSensorRaysPerBody) + " (kMaxSensorRaysPerBody), got " +
               resolution_node.Scalar());
    const int resolution = static_cast<int>(rays_per_side);
    double horizontal = 0.0, vertical = 0.0, start = 0.0;
    file.optional_non_negative(parametric, "horizontal angle", horizontal,
                               "parametric.horizontal angle");
    file.optional_non_negative(parametric, "vertical angle", vertical, "parametric.vertical angle");
    file.optional_non_negative(parametric, "start offset", start, "parametric.start offset");
    // resolution^2 rays spread over the two angles, pointing along +x of the sensor.
    for (int i = 0; i < resolution; ++i)
      for (int j = 0; j < resolution; ++j) {
        const double u = resolution > 1 ? static_cast<double>(i) / (resolution - 1) - 0.5 : 0.0;
        const double v = resolution > 1 ? static_cast<double>(j) / (resolution - 1) - 0.5 : 0.0;
        // +x turned up by the pitch (about -y), then round by the yaw (about z).
        const Vec3 direction = from_bt(
            quatRotate(rpy_rotation({0.0, -v * vertical, u * horizontal}), btVector3(1, 0, 0)));
        sensor.rays.emplace_back(
            Vec3{direction.x * start, direction.y * start, direction.z * start}, direction);
      }
  } else {
    fail(sensor.where, "'" + identifier + "' needs 'array' or 'parametric' to define its rays");
  }
  return sensor;
}

}  // namespace afhub::physics::adf
