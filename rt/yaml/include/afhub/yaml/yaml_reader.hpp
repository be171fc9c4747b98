// Reading YAML files a user writes (models, input devices, the DDS bridge's config):
// the file read whole under a size bound, parsed, and every value checked where it
// is written. Each problem is an afhub::Error "file:line:col: error: ..." that says
// what is wrong and what to write; `what` in each getter names the field.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "afhub/yaml/number_text.hpp"

namespace afhub::yaml {

// No value in afhub's files comes near this; one past it (1e308, say) overflows
// the arithmetic later, far from the file, so it is refused where it is written.
inline constexpr double kMaxMagnitude = 1e9;

// What a node is, for messages: "a map", "a list", "a value" or "nothing".
const char* kind_of(const YAML::Node& node);

// Parses `text`, the contents of `path`; a syntax error says file:line:col. A file
// past kMaxYamlNodes or kMaxYamlDepth (shm_layout/limits.hpp) is refused at the node
// that passes the bound, before any tree is built.
YAML::Node parse(const std::string& path, const std::string& text);

// Reads `path` (at most kMaxYamlFileBytes, see input_file.hpp) and parses it; the
// file must hold a map. `what` names the kind of file: "an ADF file (a map with ...)".
YAML::Node load_map(const std::string& path, const std::string& what);

// One file's nodes, read with their locations.
class Reader {
 public:
  // Warnings go to `warnings`; a reader given none refuses what it would warn of.
  explicit Reader(std::string path, std::vector<std::string>* warnings = nullptr)
      : path_(std::move(path)), warnings_(warnings) {}

  const std::string& path() const { return path_; }
  // "file:line:col" of `node`, 1-based.
  std::string where(const YAML::Node& node) const;
  [[noreturn]] void fail(const YAML::Node& node, const std::string& what) const;
  void warn(const YAML::Node& node, const std::string& what) const;
  // Warns of each key of `map` not in `known`, and refuses a key written twice (yaml-cpp
  // would take the first, most readers the last); `owner` names the map.
  void check_keys(const YAML::Node& map, const std::set<std::string>& known,
                  const std::string& owner) const;

  // A finite number of at most kMaxMagnitude in magnitude.
  double number(const YAML::Node& node, const std::string& what) const;
  // A finite number from `low` to `high`.
  double in_range(const YAML::Node& node, const std::string& what, double low, double high) const;
  double non_negative(const YAML::Node& node, const std::string& what) const;
  double positive(const YAML::Node& node, const std::string& what) const;
  bool flag(const YAML::Node& node, const std::string& what) const;
  std::string text(const YAML::Node& node, const std::string& what) const;
  // Refuses anything but a map; `example` shows one.
  void require_map(const YAML::Node& node, const std::string& what,
                   const std::string& example) const;

 private:
  double finite(const YAML::Node& node, const std::string& what) const;

  std::string path_;
  std::vector<std::string>* warnings_;
};

// A map's entries by key, indexed once: yaml-cpp searches a map's keys one by one
// on each lookup, which made looking up every body of a file quadratic. A key
// written twice is refused: which of the two is meant would be a guess.
class MapIndex {
 public:
  MapIndex(const Reader& reader, const YAML::Node& map);
  // The value at `key`, or nullptr when the map has no such key.
  const YAML::Node* find(const std::string& key) const;

 private:
  struct Entry {
    YAML::Node key, value;
  };
  std::unordered_map<std::string, Entry> entries_;
};

}  // namespace afhub::yaml
