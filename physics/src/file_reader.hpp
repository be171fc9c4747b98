// Reading AMBF files' YAML nodes with their locations, on afhub's located YAML
// reader: every value is checked and every problem thrown as afhub::Error
// "file:line:col: error: ...".
//
// Bounds. No value in a robot model comes near these; values past them (1e308,
// say) overflow Bullet's arithmetic and fail only while stepping, so they are
// refused at load with their location:
//   any number                    |x| <= 1e9 (yaml::kMaxMagnitude: gains, impulses, ...)
//   lengths: positions, offsets,  |x| <= 1e5 m (100 km)
//     pivots, shape sizes
//   mass                          <= 1e6 kg; a moving body's at least 1e-9 kg (Bullet
//                                 divides by it: 1e-300 kg blew an arm apart, 1 km)
//   scale                         > 0 and <= 1e3
#pragma once

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "afhub/physics/model.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/yaml/yaml_reader.hpp"

namespace afhub::physics {

inline constexpr double kMaxLengthM = 1e5;
inline constexpr double kMaxMassKg = 1e6;
inline constexpr double kMinMovingMassKg = 1e-9;  // a microgram
inline constexpr double kMaxScale = 1e3;

[[noreturn]] inline void fail(const SourceLocation& where, const std::string& what) {
  throw Error(where.str() + ": error: " + what);
}

inline std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return text;
}

// Reads one AMBF file's nodes with their locations: the shared located reader
// (afhub/yaml/yaml_reader.hpp) with the model's quantities and bounds.
class FileReader : public yaml::Reader {
 public:
  FileReader(std::string path, Model& model) : Reader(std::move(path), &model.warnings) {}

  SourceLocation at(const YAML::Node& node) const {
    const YAML::Mark mark = node.Mark();
    return {path(), mark.line + 1, mark.column + 1};
  }

  // A number no larger than `limit` in magnitude; `unit` names it in the message.
  double bounded(const YAML::Node& node, const std::string& what, double limit,
                 const char* unit) const {
    const double value = number(node, what);
    if (std::abs(value) > limit)
      fail(node, "'" + what + "' is " + node.Scalar() + ", beyond the bound of " +
                     yaml::number_text(limit) + " " + unit + " for a model");
    return value;
  }
  double length(const YAML::Node& node, const std::string& what) const {
    return bounded(node, what, kMaxLengthM, "m");
  }

  // Sets `out` from block[key] when the key is given; `what` names it in messages.
  void optional_non_negative(const YAML::Node& block, const char* key, double& out,
                             const std::string& what) const {
    if (YAML::Node value = block[key]) out = non_negative(value, what);
  }
  void optional_flag(const YAML::Node& block, const char* key, bool& out) const {
    if (YAML::Node value = block[key]) out = flag(value, key);
  }

  const YAML::Node require(const YAML::Node& block, const char* key,
                           const SourceLocation& where) const {
    YAML::Node value = block[key];
    if (!value) physics::fail(where, "missing '" + std::string(key) + "'");
    return value;
  }

  // {x, y, z} of lengths: positions, offsets, pivots.
  Vec3 position(const YAML::Node& node, const std::string& what) const {
    const Vec3 v = vec3(node, what);
    for (double component : {v.x, v.y, v.z})
      if (std::abs(component) > kMaxLengthM)
        fail(node, "'" + what + "' has a component of " + yaml::number_text(component) +
                       " m, beyond the bound of " + yaml::number_text(kMaxLengthM) +
                       " m for a model");
    return v;
  }

  // {x, y, z} in m/s^2. Past 10 g it is said: gravity in mm/s^2 (-9810) fell a thousand
  // times too fast, with nothing said.
  Vec3 gravity(const YAML::Node& node) const {
    const Vec3 g = vec3(node, "gravity");
    const double magnitude = std::sqrt(g.x * g.x + g.y * g.y + g.z * g.z);
    if (magnitude > 98.1)
      warn(node, "'gravity' is " + yaml::number_text(magnitude) +
                     " m/s^2, more than 10 g: ADF gives it in m/s^2 (Earth's is {x: 0, y: 0, "
                     "z: -9.81}); check its unit");
    return g;
  }

  Vec3 vec3(const YAML::Node& node, const std::string& what, const char* a = "x",
            const char* b = "y", const char* c = "z") const {
    if (!node.IsMap())
      fail(node, "'" + what + "' must be a map {" + a + ", " + b + ", " + c + "}, not " +
                     yaml::kind_of(node));
    Vec3 out;
    double* slots[3] = {&out.x, &out.y, &out.z};
    const char* keys[3] = {a, b, c};
    for (int i = 0; i < 3; ++i) {
      YAML::Node component = node[keys[i]];
      if (!component) fail(node, "'" + what + "' is missing '" + keys[i] + "'");
      *slots[i] = number(component, what + "." + keys[i]);
    }
    return out;
  }

  Vec3 axis(const YAML::Node& node, const std::string& what) const {
    Vec3 v = vec3(node, what);
    if (std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z) < 1e-9)
      fail(node, "'" + what + "' has zero length; give a direction such as {x: 0, y: 0, z: 1}");
    return v;
  }

  Placement placement(const YAML::Node& node, const std::string& what) const {
    if (!node.IsMap()) fail(node, "'" + what + "' must be a map with 'position' and 'orientation'");
    Placement out;
    if (YAML::Node position = node["position"])
      out.position_m = this->position(position, what + ".position");
    if (YAML::Node orientation = node["orientation"])
      out.rpy_rad = vec3(orientation, what + ".orientation", "r", "p", "y");
    return out;
  }
};

// A namespace key: absolute when it starts with '/', else inside `enclosing`.
inline std::string resolve_namespace(const std::string& enclosing, const std::string& given) {
  if (given.empty()) return enclosing;
  if (given.front() == '/') return given;
  return enclosing + (enclosing.ends_with('/') ? "" : "/") + given;
}

// One entry of a header list: the identifier, where it is listed, and its block.
struct ListedBlock {
  std::string identifier;
  YAML::Node listed;
  YAML::Node block;
};

// The blocks a header list names, with where each one is listed.
inline std::vector<ListedBlock> header_list(const FileReader& file, const yaml::MapIndex& index,
                                            const char* key) {
  std::vector<ListedBlock> out;
  const YAML::Node* list = index.find(key);
  if (!list) return out;
  if (!list->IsSequence())
    fail(file.at(*list),
         std::string("'") + key + "' must be a list of identifiers, e.g. [BODY base]");
  for (const auto& item : *list) {
    std::string identifier = file.text(item, std::string(key) + " entry");
    const YAML::Node* block = index.find(identifier);
    if (!block)
      fail(file.at(item), "'" + identifier + "' is listed in '" + key +
                              "' but the file has no top-level '" + identifier +
                              "' block; add the block or remove it from the list");
    out.push_back({identifier, item, *block});
  }
  return out;
}

}  // namespace afhub::physics
