// A controller in a few lines: joint 0 of a body swings +-0.5 rad at 0.5 Hz around
// where it started, the other joints hold. Build it against an installed afhub
// (see CMakeLists.txt beside it), start a simulation, and run:
//   ./wave_controller base            (Ctrl-C to stop; `afhub top` shows its timing)
#include <afhub/controllers/controller.hpp>
#include <afhub/shm_layout/error.hpp>
#include <cmath>
#include <cstdio>
#include <exception>
#include <numbers>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s BODY\n", argv[0]);
    return 2;
  }
  afhub::ControllerOptions options;
  options.name = "wave example";
  options.body = argv[1];
  afhub::BodyState start;  // the first state seen
  bool started = false;
  try {
    return afhub::run_controller(
        options, [&](const afhub::BodyState& state, afhub::BodyCommand& command) {
          if (!started) {
            // The state in shared memory holds only its own joints: copy that much.
            afhub::copy_body_state(state, start);
            started = true;
          }
          const double t = state.header.sim_time_s - start.header.sim_time_s;
          for (std::uint32_t j = 0; j < command.joint_count; ++j) {
            command.joints[j].type = afhub::JointCommandType::kPosition;
            command.joints[j].value = start.joints[j].position;
          }
          if (command.joint_count > 0)
            command.joints[0].value += 0.5 * std::sin(std::numbers::pi * t);
        });
  } catch (const std::exception& error) {  // afhub::Error, and any other
    std::fprintf(stderr, "wave_controller: error: %s\n", error.what());
    return 1;
  }
}
