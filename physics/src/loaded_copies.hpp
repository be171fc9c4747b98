// A model loaded twice (`afhub run arm.yaml arm.yaml`, two input devices bound to one
// gripper file) gets distinct channels as AMBF names them: a body whose channel an
// earlier file already uses gets the smallest index that makes it free appended to
// its name ("ambf/env/base" -> "ambf/env/base1", then "base2"). Joints keep their
// names (a body's joint list is its own) and get the same index on their channel.
// Internal to the loader.
#pragma once

#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "adf_blocks.hpp"

namespace afhub::physics::adf {

// What one file added to the model, from these indices on: its joints are pending
// (ADF, resolved once every file is read) or already in the model (URDF).
struct FileSpan {
  std::string path;
  std::size_t first_body = 0, first_soft_body = 0, first_joint = 0, first_model_joint = 0;
};

class LoadedChannels {
 public:
  // Renames what the file `span` added whose channel an earlier file uses, writes
  // each body's index into `copy_suffix` (grown to the bodies' count; "" when kept),
  // warns once for the file, then records its channels.
  void load_as_copies(const FileSpan& span, Model& model, std::vector<PendingJoint>& joints,
                      std::vector<std::string>& copy_suffix);

 private:
  // The channel, or the first channel + index free in `taken` and not one of `own`.
  static std::string free_name(const std::string& channel,
                               const std::unordered_map<std::string, SourceLocation>& taken,
                               const std::unordered_set<std::string>& own);
  std::unordered_map<std::string, SourceLocation> bodies_, joints_;
};

}  // namespace afhub::physics::adf
