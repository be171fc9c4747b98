// Reading YAML nodes of AMBF files with their locations: every value is checked
// and every problem thrown as afhub::Error "file:line:col: error: ...".
#pragma once

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <string>

#include "afhub/physics/model.hpp"
#include "afhub/shm_layout/error.hpp"

namespace afhub::physics {

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
    return value;
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
    if (YAML::Node position = node["position"]) out.position_m = vec3(position, what + ".position");
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

// The identifiers a header list names, with where each one is written.
inline std::vector<std::pair<std::string, YAML::Node>> header_list(const FileReader& file,
                                                                   const YAML::Node& root,
                                                                   const char* key) {
  std::vector<std::pair<std::string, YAML::Node>> out;
  YAML::Node list = root[key];
  if (!list) return out;
  if (!list.IsSequence())
    fail(file.at(list),
         std::string("'") + key + "' must be a list of identifiers, e.g. [BODY base]");
  for (const auto& item : list) {
    std::string identifier = file.text(item, std::string(key) + " entry");
    if (!root[identifier])
      fail(file.at(item), "'" + identifier + "' is listed in '" + key +
                              "' but the file has no top-level '" + identifier +
                              "' block; add the block or remove it from the list");
    out.emplace_back(identifier, item);
  }
  return out;
}

// Parses a YAML file that must hold a map; `what` names the kind of file in messages.
inline YAML::Node parse_file(const std::string& path, const std::string& what) {
  if (!std::filesystem::is_regular_file(path)) throw Error(path + ": error: no such file");
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::ParserException& error) {
    throw Error(path + ":" + std::to_string(error.mark.line + 1) + ":" +
                std::to_string(error.mark.column + 1) + ": error: YAML syntax: " + error.msg);
  }
  if (root.IsNull()) throw Error(path + ":1:1: error: the file is empty; expected " + what);
  if (!root.IsMap()) throw Error(path + ":1:1: error: expected " + what + ", not " + kind_of(root));
  return root;
}

}  // namespace afhub::physics
