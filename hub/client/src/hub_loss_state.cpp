// The state of a process that outlives its hub (see hub_loss_state.hpp).
#include "hub_loss_state.hpp"

namespace afhub::hub_loss {

State& state() {
  static State* state = new State;
  return *state;
}

}  // namespace afhub::hub_loss
