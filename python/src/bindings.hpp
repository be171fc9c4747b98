// What the parts of the Python module share: the registration of each part, the
// connection to the hub made on first use, and conversions between Python
// sequences and afhub's geometric types.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <exception>
#include <optional>
#include <string>

#include "afhub/hub/bodies.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/geometry.hpp"

namespace afhub::python {

namespace py = pybind11;

void register_body(py::module_& module);
void register_device(py::module_& module);
void register_loop(py::module_& module);
void register_world(py::module_& module);

// Joins the hub once per process (as "afhub-python-<pid>"), waiting up to `wait_s` for
// it; throws afhub::Error saying how to start one when none runs, or require_hub's.
void ensure_connected(double wait_s = 0.0);

// Throws hub_gone() once the hub this process joined went away: a process cannot
// re-attach to another (iceoryx's runtime is one per process), and what it would read
// is frozen. Called before every use of the hub, so that none meets iceoryx's fatal
// errors after the loss.
void require_hub();
Error hub_gone();

// The catalog entry of the body or device `name`, waiting up to `wait_s` for it to
// come (connecting first); afhub::Error when none comes, or hub_gone() when the hub
// went away meanwhile. `kind` ("body", "device") names what it waits for.
BodyEntry wait_for_entry(const std::string& name, double wait_s, const char* kind);

// Exactly `size` finite numbers from any Python sequence or array; ValueError naming
// `what` otherwise.
py::array_t<double> finite_values(const py::handle& values, const char* what,
                                  std::optional<std::size_t> size = std::nullopt);
Vec3 to_vec3(const py::handle& values, const char* what);
Quaternion to_quaternion(const py::handle& values, const char* what);  // x, y, z, w

// A read-only numpy view of `count` doubles from `first`, `stride` bytes apart, kept
// alive by `owner`.
py::array view(const double* first, std::size_t count, std::size_t stride, py::handle owner);

// ValueError when `name` holds a NUL: it names no channel, and a message naming it would
// end there.
void require_no_nul(const std::string& name);

// Seconds to a CLOCK_MONOTONIC deadline; ValueError unless 0 <= seconds <= 1e6.
std::int64_t deadline_after(double seconds, const char* what);

// Ctrl-C during a wait with the GIL released: a signal's Python handler runs only under
// the GIL, so the wait looks for it, at most every 20 ms (a look takes the GIL).
// pending() keeps the exception (KeyboardInterrupt) for raise_if_pending(), which raises
// it once the GIL is held again. One state for the process, kept by its main thread
// (the only one Python runs signal handlers on; elsewhere nothing is pending): a Ctrl-C
// seen by any wait, the hub client's own included, is raised by the next
// raise_if_pending(), never lost between two watches.
class SignalWatch {
 public:
  bool pending() noexcept;  // without the GIL
  void raise_if_pending();  // with the GIL
  static constexpr std::int64_t kLookEveryNs = 20'000'000;
};

// Makes a pending Ctrl-C end the hub client's own waits too (for a hub, for a body: they
// look at stop_requested()). Called once, at import.
void watch_interrupts_in_waits();

}  // namespace afhub::python
