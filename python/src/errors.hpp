// The module's exceptions: afhub.Error (afhub::Error's message, a RuntimeError) and
// afhub.CommandRefused (a command the physics refused, with its reason).
#pragma once

#include <pybind11/pybind11.h>

#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/loop_stats.hpp"

namespace afhub::python {

class CommandRefused : public Error {
 public:
  using Error::Error;
};

inline void register_errors(pybind11::module_& module) {
  // Registered base first: pybind11 tries the newest translator first.
  const auto& base = pybind11::register_exception<Error>(module, "Error", PyExc_RuntimeError);
  base.doc() = "An afhub failure, with what is wrong and what to do (the CLI's messages).";
  pybind11::register_exception<CommandRefused>(module, "CommandRefused", base.ptr()).doc() =
      "The physics refused a command of this process (nothing of it was applied).";
}

// A loop's statistics as a dict (afhub.loop_stats, Loop.run).
pybind11::dict loop_stats_dict(const LoopStats& stats);

}  // namespace afhub::python
