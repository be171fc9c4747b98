// A client killed in the middle of updating its slots: it commands synth/body0 once
// and publishes one state of torn/body (step 1), taped on world "torn"'s step tape as a
// physics does; once readers hold both slots and the tape, and the file named by its
// argument exists (the readers have their copies), it begins an update of each slot
// and the next step's tape, writes half of each, and SIGKILLs itself, leaving the
// slots and the tape's part torn (their sequence odd). Exits 2 if no reader comes, or
// no file, in 10 s.
#include <signal.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <thread>

#include "afhub/hub/channel.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/step_tape.hpp"
#include "afhub/shm_layout/body_command.hpp"
#include "afhub/shm_layout/body_state.hpp"

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  afhub::connect_to_hub("torn-writer", afhub::HubPolicy::kRequire);
  afhub::Writer<afhub::BodyCommand> commands(afhub::body_command_channel("synth/body0"));
  afhub::Writer<afhub::BodyState> states(afhub::body_state_channel("torn/body"));
  afhub::StepTapeWriter tape("torn");
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  auto wait_for = [&](auto ready, const char* what) {
    while (!ready()) {
      if (std::chrono::steady_clock::now() > deadline) {
        std::fprintf(stderr, "torn_slot_writer: %s within 10 s\n", what);
        std::exit(2);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  };
  afhub::BodyCommand* command = commands.loan(afhub::body_command_bytes(1));
  afhub::BodyState* state = states.loan(afhub::body_state_bytes(1));
  if (!command || !state) {
    std::fprintf(stderr, "torn_slot_writer: no shared memory to write\n");
    return 2;
  }
  command->joint_count = 1;
  command->joints[0].type = afhub::JointCommandType::kPosition;
  command->joints[0].value = 0.2;
  commands.publish(command);
  state->joint_count = 1;
  state->header.sim_step = 1;
  states.publish(state);
  wait_for([&] { return commands.raw().has_readers() && states.raw().has_readers(); },
           "no readers");
  wait_for([&] { return tape.begin(1, 0.001); }, "no reader of the tape");
  tape.add(afhub::PayloadKind::kBodyState, "torn/body", state, afhub::body_state_bytes(1));
  tape.finish();
  wait_for([&] { return std::filesystem::exists(argv[1]); }, "no go-ahead");
  // The updates it dies in: half written, and absurd.
  command = commands.loan(afhub::body_command_bytes(1));
  state = states.loan(afhub::body_state_bytes(1));
  command->joints[0].value = 1e300;
  state->header.sim_step = 2;
  std::memset(static_cast<void*>(&state->pose), 0xff, sizeof state->pose);
  tape.begin(2, 0.002);
  tape.add(afhub::PayloadKind::kBodyState, "torn/body", state, afhub::body_state_bytes(1));
  raise(SIGKILL);
}
