// The simulation embedded in a program of your own, with no hub and no channels:
// load an AMBF model, give a body position targets for its joints, step, read the
// joints back. Build it against an installed afhub (see CMakeLists.txt beside it):
//   ./embedded_simulation <prefix>/share/afhub/models/arm7.yaml base 0.5 2.0
// drives every joint below the body `base` to 0.5 rad for 2 s and prints them.
#include <afhub/physics/adf_loader.hpp>
#include <afhub/physics/simulation.hpp>
#include <afhub/shm_layout/error.hpp>
#include <cstdio>
#include <exception>
#include <string>

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: %s MODEL.yaml BODY TARGET_RAD SECONDS\n", argv[0]);
    return 2;
  }
  try {
    const afhub::physics::Model model = afhub::physics::load_adf_files({argv[1]});
    afhub::physics::Simulation sim(model, 0.001);
    std::size_t body = 0;
    while (body < model.bodies.size() && model.bodies[body].name != argv[2]) ++body;
    if (body == model.bodies.size()) throw afhub::Error(std::string("no body named ") + argv[2]);

    // The body's descendant joints, in the order its inputs and readings use.
    const auto joint_count = static_cast<std::uint32_t>(model.descendant_joints[body].size());
    afhub::physics::BodyInput input;
    input.joint_count = joint_count;
    for (std::uint32_t j = 0; j < input.joint_count; ++j) {
      input.joint_modes[j] = afhub::physics::JointMode::kPosition;
      input.joint_values[j] = std::stod(argv[3]);
    }
    if (const char* problem = afhub::physics::input_problem(input, joint_count))
      throw afhub::Error(problem);
    const double seconds = std::stod(argv[4]);
    while (sim.time_s() < seconds) {
      sim.set_input(body, input);
      sim.step();
    }
    std::printf("after %.3f s (%llu steps):\n", sim.time_s(),
                static_cast<unsigned long long>(sim.step_count()));
    for (std::size_t j = 0; j < model.joints.size(); ++j)
      std::printf("%-32s %9.4f\n", model.joints[j].channel.c_str(), sim.joint_position(j));
    return 0;
  } catch (const std::exception& error) {  // afhub::Error, and any other (std::stod's)
    std::fprintf(stderr, "embedded_simulation: error: %s\n", error.what());
    return 1;
  }
}
