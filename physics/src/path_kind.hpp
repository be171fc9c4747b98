// Why a path a model names is not a regular file, for its error message: a mesh that
// is a directory, a FIFO or /dev/zero is not "not found".
#pragma once

#include <filesystem>
#include <string>

namespace afhub::physics {

// "does not exist", "is a directory", "is a FIFO", "is a character device", "is a
// symlink loop", "is a broken symlink to 'x'", ...; empty for a regular file.
std::string not_a_regular_file(const std::filesystem::path& path);

}  // namespace afhub::physics
