// The generated scene of `afhub bench bodies` (and of the physics benchmarks and tests
// that need many bodies): `arms` arms of `links` links each, every link an active body
// (a state and a command slot each) and every joint a revolute one under a PD
// controller. 125 arms of 8 links are issue 30's thousand bodies. The arms stand 1 m
// apart on a grid 12 wide, each base fixed, their links not colliding with each other's.
#pragma once

#include <string>

namespace afhub::bench {

// ADF text (namespace /arms/: the bodies are arms/a<arm>l<link>).
std::string arms_scene(int arms, int links);

}  // namespace afhub::bench
