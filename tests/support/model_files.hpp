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

// A generated scene of `arms` arms of `links` links each, every link an active body
// (a state slot each) and every joint a revolute one under a PD controller: 125 arms of
// 8 links are the thousand bodies of issue 30. The arms stand 1 m apart, each base fixed.
inline std::string arms_model(int arms, int links) {
  std::string text = "adf version: '1.0'\nnamespace: /arms/\n";
  text += "gravity: {x: 0.0, y: 0.0, z: -9.81}\nignore inter-collision: true\nbodies: [";
  for (int a = 0; a < arms; ++a)
    for (int l = 0; l < links; ++l)
      text += (a || l ? ", " : "") + std::string("BODY a") + std::to_string(a) + "l" +
              std::to_string(l);
  text += "]\njoints: [";
  for (int a = 0; a < arms; ++a)
    for (int l = 1; l < links; ++l)
      text += (a || l > 1 ? ", " : "") + std::string("JOINT a") + std::to_string(a) + "j" +
              std::to_string(l);
  text += "]\n";
  for (int a = 0; a < arms; ++a) {
    const std::string arm = "a" + std::to_string(a);
    const std::string x = std::to_string(a % 12), y = std::to_string(a / 12);
    for (int l = 0; l < links; ++l)
      text += "BODY " + arm + "l" + std::to_string(l) + ":\n  name: " + arm + "l" +
              std::to_string(l) + "\n  mass: " + (l ? "1.0" : "0.0") +
              "\n  inertia: {ix: 0.01, iy: 0.01, iz: 0.01}\n  shape: box\n"
              "  geometry: {x: 0.05, y: 0.05, z: 0.1}\n  location:\n    position: {x: " +
              x + ", y: " + y + ", z: " + std::to_string(0.1 * l) + "}\n";
    for (int l = 1; l < links; ++l)
      text += "JOINT " + arm + "j" + std::to_string(l) + ":\n  name: " + arm + "j" +
              std::to_string(l) + "\n  parent: BODY " + arm + "l" + std::to_string(l - 1) +
              "\n  child: BODY " + arm + "l" + std::to_string(l) +
              "\n  type: revolute\n  parent pivot: {x: 0, y: 0, z: 0.05}\n"
              "  parent axis: {x: 0, y: " +
              (l % 2 ? "1" : "0") + ", z: " + (l % 2 ? "0" : "1") +
              "}\n  child pivot: {x: 0, y: 0, z: -0.05}\n  child axis: {x: 0, y: " +
              (l % 2 ? "1" : "0") + ", z: " + (l % 2 ? "0" : "1") +
              "}\n  controller: {P: 50.0, I: 0.0, D: 2.0}\n";
  }
  return text;
}

}  // namespace afhub::testing
