// Reading YAML nodes of AMBF files with their locations: every value is checked
// and every problem thrown as afhub::Error "file:line:col: error: ...".
//
// Bounds. No value in a robot model comes near these; values past them (1e308,
// say) overflow Bullet's arithmetic and fail only while stepping, so they are
// refused at load with their location:
//   any number                    |x| <= 1e9 (gains, stiffness, impulses, ...)
//   lengths: positions, offsets,  |x| <= 1e5 m (100 km)
//     pivots, shape sizes
//   mass                          <= 1e6 kg
//   scale                         > 0 and <= 1e3
#pragma once

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <string>
#include <unordered_map>

#include "afhub/physics/model.hpp"
#include "afhub/shm_layout/error.hpp"
#include "input_file.hpp"

namespace afhub::physics {

inline constexpr double kMaxMagnitude = 1e9;
inline constexpr double kMaxLengthM = 1e5;
inline constexpr double kMaxMassKg = 1e6;
inline constexpr double kMaxScale = 1e3;

[[noreturn]] inline void fail(const SourceLocation& where, const std::string& what) {
  throw Error(where.str() + ": error: " + what);
}

inline std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return text;
}

inline const char* kind_of(const YAML::Node& node) {
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

// Reads one file's nodes with their locations.
class FileReader {
 public:
  FileReader(std::string path, Model& model) : path_(std::move(path)), model_(model) {}

  SourceLocation at(const YAML::Node& node) const {
    const YAML::Mark mark = node.Mark();
    return {path_, mark.line + 1, mark.column + 1};
  }

  double number(const YAML::Node& node, const std::string& what) const {
    if (!node.IsScalar()) fail(at(node), "'" + what + "' must be a number, not " + kind_of(node));
    double value = 0.0;
    if (!YAML::convert<double>::decode(node, value))
      fail(at(node), "'" + what + "' must be a number, got '" + node.Scalar() + "'");
    if (!std::isfinite(value))
      fail(at(node), "'" + what + "' must be finite, got '" + node.Scalar() + "'");
    if (std::abs(value) > kMaxMagnitude)
      fail(at(node), "'" + what + "' is " + node.Scalar() +
                         ", beyond any physical value (at most " + bound_text(kMaxMagnitude) +
                         " in magnitude)");
    return value;
  }

  // A number no larger than `limit` in magnitude; `unit` names it in the message.
  double bounded(const YAML::Node& node, const std::string& what, double limit,
                 const char* unit) const {
    const double value = number(node, what);
    if (std::abs(value) > limit)
      fail(at(node), "'" + what + "' is " + node.Scalar() + ", beyond the bound of " +
                         bound_text(limit) + " " + unit + " for a model");
    return value;
  }
  double length(const YAML::Node& node, const std::string& what) const {
    return bounded(node, what, kMaxLengthM, "m");
  }

  static std::string bound_text(double limit) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", limit);
    return text;
  }

  double non_negative(const YAML::Node& node, const std::string& what) const {
    double value = number(node, what);
    if (value < 0.0) fail(at(node), "'" + what + "' must not be negative, got " + node.Scalar());
    return value;
  }

  bool flag(const YAML::Node& node, const std::string& what) const {
    bool value = false;
    if (!node.IsScalar() || !YAML::convert<bool>::decode(node, value))
      fail(at(node), "'" + what + "' must be true or false");
    return value;
  }

  std::string text(const YAML::Node& node, const std::string& what) const {
    if (!node.IsScalar()) fail(at(node), "'" + what + "' must be text, not " + kind_of(node));
    return node.Scalar();
  }

  void require_map(const YAML::Node& node, const std::string& what,
                   const std::string& example) const {
    if (!node.IsMap())
      fail(at(node), "'" + what + "' must be a map such as " + example + ", not " + kind_of(node));
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
    if (!value) fail(where, "missing '" + std::string(key) + "'");
    return value;
  }

  // {x, y, z} of lengths: positions, offsets, pivots.
  Vec3 position(const YAML::Node& node, const std::string& what) const {
    const Vec3 v = vec3(node, what);
    for (double component : {v.x, v.y, v.z})
      if (std::abs(component) > kMaxLengthM)
        fail(at(node), "'" + what + "' has a component of " + bound_text(component) +
                           " m, beyond the bound of " + bound_text(kMaxLengthM) + " m for a model");
    return v;
  }

  Vec3 vec3(const YAML::Node& node, const std::string& what, const char* a = "x",
            const char* b = "y", const char* c = "z") const {
    if (!node.IsMap())
      fail(at(node),
           "'" + what + "' must be a map {" + a + ", " + b + ", " + c + "}, not " + kind_of(node));
    Vec3 out;
    double* slots[3] = {&out.x, &out.y, &out.z};
    const char* keys[3] = {a, b, c};
    for (int i = 0; i < 3; ++i) {
      YAML::Node component = node[keys[i]];
      if (!component) fail(at(node), "'" + what + "' is missing '" + keys[i] + "'");
      *slots[i] = number(component, what + "." + keys[i]);
    }
    return out;
  }

  Vec3 axis(const YAML::Node& node, const std::string& what) const {
    Vec3 v = vec3(node, what);
    if (std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z) < 1e-9)
      fail(at(node), "'" + what + "' has zero length; give a direction such as {x: 0, y: 0, z: 1}");
    return v;
  }

  Placement placement(const YAML::Node& node, const std::string& what) const {
    if (!node.IsMap())
      fail(at(node), "'" + what + "' must be a map with 'position' and 'orientation'");
    Placement out;
    if (YAML::Node position = node["position"])
      out.position_m = this->position(position, what + ".position");
    if (YAML::Node orientation = node["orientation"])
      out.rpy_rad = vec3(orientation, what + ".orientation", "r", "p", "y");
    return out;
  }

  void warn(const YAML::Node& node, const std::string& what) const {
    model_.warnings.push_back(at(node).str() + ": warning: " + what);
  }

  void warn_unknown_keys(const YAML::Node& block, const std::set<std::string>& known,
                         const std::string& owner) const {
    for (const auto& entry : block) {
      const std::string key = entry.first.Scalar();
      if (!known.count(key))
        warn(entry.first, "unknown key '" + key + "' in " + owner + " is ignored");
    }
  }

  const std::string& path() const { return path_; }

 private:
  std::string path_;
  Model& model_;
};

// A namespace key: absolute when it starts with '/', else inside `enclosing`.
inline std::string resolve_namespace(const std::string& enclosing, const std::string& given) {
  if (given.empty()) return enclosing;
  if (given.front() == '/') return given;
  return enclosing + (enclosing.ends_with('/') ? "" : "/") + given;
}

// A map's entries by key, indexed once. yaml-cpp searches a map's keys one by one
// on each lookup, so looking up every body of a file in its top-level map made
// loading quadratic in the bodies. A key written twice is refused: which of the
// two would be meant is a guess.
class MapIndex {
 public:
  MapIndex(const FileReader& file, const YAML::Node& map) {
    for (const auto& entry : map) {
      const YAML::Node& key = entry.first;
      const std::string name = key.IsScalar() ? key.Scalar() : std::string();
      auto [found, added] = entries_.try_emplace(name, Entry{key, entry.second});
      if (!added && key.IsScalar())
        fail(file.at(key), "'" + name + "' is written twice in this map (first at " +
                               file.at(found->second.key).str() + "); keep one");
    }
  }
  // The value at `key`, or nullptr when the map has no such key.
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

// One entry of a header list: the identifier, where it is listed, and its block.
struct ListedBlock {
  std::string identifier;
  YAML::Node listed;
  YAML::Node block;
};

// The blocks a header list names, with where each one is listed.
inline std::vector<ListedBlock> header_list(const FileReader& file, const MapIndex& index,
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

// Model and description files are read whole before parsing; none comes near this.
inline constexpr std::uintmax_t kMaxDescriptionFileBytes = 64u << 20;

// Parses a YAML file that must hold a map; `what` names the kind of file in messages.
inline YAML::Node parse_file(const std::string& path, const std::string& what) {
  const std::string text = read_input_file(path, kMaxDescriptionFileBytes, what);
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& error) {
    throw Error(path + ":" + std::to_string(error.mark.line + 1) + ":" +
                std::to_string(error.mark.column + 1) + ": error: YAML syntax: " + error.msg);
  } catch (const YAML::Exception& error) {
    throw Error(path + ": error: YAML: " + error.msg);
  }
  if (root.IsNull()) throw Error(path + ":1:1: error: the file is empty; expected " + what);
  if (!root.IsMap()) throw Error(path + ":1:1: error: expected " + what + ", not " + kind_of(root));
  return root;
}

}  // namespace afhub::physics
