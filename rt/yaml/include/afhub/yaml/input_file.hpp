// Files named by a user, checked before anything parses them: that they exist, are
// regular files the user may read, and are not larger than a bound. Each problem
// is an afhub::Error naming the file and saying what is wrong. yaml_reader.hpp reads
// YAML files through it; the physics checks its meshes with it.
#pragma once

#include <cstdint>
#include <string>

namespace afhub::yaml {

// Checks that `path` is a readable regular file of at most `max_bytes`; returns its
// size. `what` names the kind of file in messages ("a mesh", "an ADF file ...").
std::uintmax_t check_input_file(const std::string& path, std::uintmax_t max_bytes,
                                const std::string& what);

// Checks `path` as above and returns its contents.
std::string read_input_file(const std::string& path, std::uintmax_t max_bytes,
                            const std::string& what);

}  // namespace afhub::yaml
