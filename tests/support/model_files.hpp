// Test models written on the fly into a private temporary folder, and a generated one.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace afhub::testing {

class ModelFolder {
 public:
  ModelFolder() {
    static int counter = 0;
    dir_ = std::filesystem::temp_directory_path() /
           ("afhub_models_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::filesystem::create_directories(dir_);
  }
  ~ModelFolder() { std::filesystem::remove_all(dir_); }
  ModelFolder(const ModelFolder&) = delete;
  ModelFolder& operator=(const ModelFolder&) = delete;

  // Writes `text` to `name` in the folder; returns its path.
  std::string write(const std::string& name, const std::string& text) const {
    const auto path = dir_ / name;
    std::ofstream(path) << text;
    return path.string();
  }
  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
};

// A model of `count` passive spheres (BODY b0, b1, ...) all at the origin: every pair
// of them overlaps. Passive bodies publish nothing: any number of them stay within the
// hub's limit.
inline std::string passive_spheres_at_origin(int count) {
  std::string text = "bodies: [";
  for (int i = 0; i < count; ++i) text += (i ? ", BODY b" : "BODY b") + std::to_string(i);
  text += "]\n";
  for (int i = 0; i < count; ++i)
    text += "BODY b" + std::to_string(i) + ":\n  name: b" + std::to_string(i) +
            "\n  mass: 1\n  passive: true\n  shape: sphere\n  geometry: {radius: 0.1}\n";
  return text;
}

}  // namespace afhub::testing
