// A model file moved elsewhere in the world, for scenes with several copies of one
// robot: copies loaded where their file puts them would overlap and push each other
// apart, breaking their loops. The copy is written outside the project (a temporary
// folder); the model itself is never copied into the repository.
#pragma once

#include <string>

namespace afhub::testing {

// The ADF text of `path` with every body's `location: position` moved by (dx, dy, dz)
// metres and its relative mesh folders made absolute, so that the copy loads from
// any folder. Throws std::runtime_error naming the file when it cannot be read.
std::string placed_copy(const std::string& path, double dx, double dy, double dz);

}  // namespace afhub::testing
