// Finding the example models (see example_models.hpp).
#include "example_models.hpp"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>

#include "afhub/shm_layout/error.hpp"

namespace afhub::cli {

std::string example_models_dir() {
  if (const char* env = std::getenv("AFHUB_MODELS"); env && *env) {
    if (!std::filesystem::is_directory(env))
      throw Error(std::string("$AFHUB_MODELS is ") + env + ", which is not a folder");
    return env;
  }
  std::error_code error;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", error);
  const auto dir = (self.parent_path() / ".." / "share" / "afhub" / "models").lexically_normal();
  if (error || !std::filesystem::is_directory(dir))
    throw Error("the example models are not installed at " + dir.string() +
                " (beside this afhub); reinstall afhub, or set AFHUB_MODELS to their folder");
  return dir.string();
}

std::string example_model(const std::string& file) {
  return (std::filesystem::path(example_models_dir()) / file).string();
}

}  // namespace afhub::cli
