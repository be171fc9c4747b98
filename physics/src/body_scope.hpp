// Which body a joint's, sensor's or actuator's `parent` / `child` names, by AMBF's
// rule: the referring block's own file first, then the namespace-qualified name
// ("/ambf/env/psm/BODY base link"), then every loaded file. Several files may so
// use the same block names, each in its own scope. Internal to the loader.
#pragma once

#include <string>
#include <unordered_map>
#include <vector>

#include "afhub/physics/model.hpp"

namespace afhub::physics::adf {

// Where a reference was written: its file and the namespace of its block.
struct Referrer {
  int file_index = 0;
  std::string name_space;
};

// "/ambf/env/" + "BODY a" as "/ambf/env/BODY a": how other files may name a body.
std::string qualified_identifier(const std::string& name_space, const std::string& identifier);

class BodyScope {
 public:
  // Indexes every body of `model`. `copy_suffix[b]` is what a body loaded as a copy
  // got appended to its name ("" for the others): "/ambf/env/BODY a1" names it too.
  BodyScope(const Model& model, const std::vector<std::string>& copy_suffix);

  // The body `reference` names, seen from `from`; a located error when no loaded
  // body or more than one matches (the candidates listed with files and namespaces).
  int find(const std::string& reference, const Referrer& from, const SourceLocation& where,
           const std::string& role, const std::string& owner) const;

 private:
  const Model& model_;
  const std::vector<std::string>& copy_suffix_;
  std::unordered_map<std::string, int> in_file_;  // "<file index>\n<identifier>"
  std::unordered_map<std::string, std::vector<int>> by_qualified_, by_identifier_;
};

}  // namespace afhub::physics::adf
