// Where the project's own example models are: installed beside the executable
// (<prefix>/share/afhub/models for <prefix>/bin/afhub; the build tree has the same
// shape), or wherever $AFHUB_MODELS points.
#pragma once

#include <string>

namespace afhub::cli {

// The folder of the example models; throws afhub::Error saying where it looked.
std::string example_models_dir();

// A file in that folder, e.g. example_model("arm7.yaml").
std::string example_model(const std::string& file);

}  // namespace afhub::cli
