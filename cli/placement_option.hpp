// `--at FILE=x,y,z[,r,p,y]`, for `afhub run` and `check`: where a loaded file's bodies go
// (physics::parse_file_placement reads each).
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace afhub::cli {

inline void add_placement_option(CLI::App* command, std::vector<std::string>& placements) {
  command
      ->add_option("--at", placements,
                   "Place a loaded file's bodies: FILE=x,y,z or FILE=x,y,z,r,p,y (metres; roll, "
                   "pitch, yaw in radians), every body of FILE moved so, about the world's "
                   "origin; repeat for more files (of a file loaded twice, each places the next "
                   "copy). AMBF draws its robots at the origin, where loaded together they "
                   "overlap and push each other apart")
      ->allow_extra_args(false);  // one FILE=... each: files may follow
}

}  // namespace afhub::cli
