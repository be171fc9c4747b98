// The generated scene of many arms (see arms_scene.hpp).
#include "afhub/bench/arms_scene.hpp"

namespace afhub::bench {

std::string arms_scene(int arms, int links) {
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
    // Axes alternate between y and z, so that the arm moves in 3D.
    for (int l = 1; l < links; ++l) {
      const std::string axis = l % 2 ? "{x: 0, y: 1, z: 0}" : "{x: 0, y: 0, z: 1}";
      text += "JOINT " + arm + "j" + std::to_string(l) + ":\n  name: " + arm + "j" +
              std::to_string(l) + "\n  parent: BODY " + arm + "l" + std::to_string(l - 1) +
              "\n  child: BODY " + arm + "l" + std::to_string(l) +
              "\n  type: revolute\n  parent pivot: {x: 0, y: 0, z: 0.05}\n  parent axis: " + axis +
              "\n  child pivot: {x: 0, y: 0, z: -0.05}\n  child axis: " + axis +
              "\n  controller: {P: 50.0, I: 0.0, D: 2.0}\n";
    }
  }
  return text;
}

}  // namespace afhub::bench
