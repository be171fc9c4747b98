// The Python module `afhub`: a process joins the hub and reads and commands bodies,
// devices and the world in shared memory through the project's hub client.
#include <pybind11/stl.h>

#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/body_world.hpp"
#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/loop_stats_reader.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "bindings.hpp"
#include "errors.hpp"

namespace afhub::python {

void ensure_connected(double wait_s) {
  // Checked first: connected already, connect(wait_s=nan) returned as if it were good.
  if (!(wait_s >= 0.0 && wait_s <= 1e6)) throw py::value_error("wait_s takes 0 to 1e6 seconds");
  require_hub();
  if (!runtime_name().empty()) return;
  try {
    py::gil_scoped_release release;
    notice_hub_loss("python");
    connect_to_hub("python", HubPolicy::kRequire,
                   std::chrono::milliseconds(static_cast<std::int64_t>(wait_s * 1000.0)));
  } catch (const Error&) {
    SignalWatch().raise_if_pending();  // Ctrl-C ended the wait
    throw;
  }
}

void require_hub() {
  if (hub_lost()) throw hub_gone();
}

Error hub_gone() {
  return Error(
      "the hub this process joined went away: a process cannot join another one (iceoryx "
      "allows one per process), so start the script again once a hub runs");
}

void require_no_nul(const std::string& name) {
  if (name.find('\0') != std::string::npos)
    throw py::value_error("a name has no NUL character; got one at index " +
                          std::to_string(name.find('\0')));
}

BodyEntry wait_for_entry(const std::string& name, double wait_s, const char* kind) {
  require_no_nul(name);
  ensure_connected();
  const std::int64_t give_up = deadline_after(wait_s, "wait_s");
  try {
    py::gil_scoped_release release;
    return wait_for_body(name, "afhub python", give_up, "wait longer with wait_s", kind);
  } catch (const Error&) {
    SignalWatch().raise_if_pending();  // Ctrl-C ended the wait
    require_hub();                     // what the catalog of a hub gone says is beside the point
    throw;
  }
}

py::array_t<double> finite_values(const py::handle& values, const char* what,
                                  std::optional<std::size_t> size) {
  // Real numbers only: numpy would cast strings, booleans, dates (days as radians) and
  // complex numbers (their imaginary part dropped).
  const py::array given = py::array::ensure(values);
  if (!given || given.ndim() != 1)
    throw py::value_error(std::string(what) + " takes a sequence of numbers");
  if (const char kind = given.dtype().kind(); kind != 'f' && kind != 'i' && kind != 'u')
    throw py::value_error(std::string(what) + " takes a sequence of real numbers, not of " +
                          py::str(given.dtype()).cast<std::string>());
  auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(given);
  if (!array) throw py::value_error(std::string(what) + " takes a sequence of numbers");
  if (size && static_cast<std::size_t>(array.size()) != *size)
    throw py::value_error(std::string(what) + " takes " + std::to_string(*size) + " numbers, not " +
                          std::to_string(array.size()));
  const double* data = array.data();
  for (py::ssize_t i = 0; i < array.size(); ++i)
    if (!std::isfinite(data[i]))
      throw py::value_error(std::string(what) + "[" + std::to_string(i) + "] is " +
                            py::str(py::float_(data[i])).cast<std::string>() +
                            ", not a finite number: nothing was sent");
  return array;
}

Vec3 to_vec3(const py::handle& values, const char* what) {
  const auto array = finite_values(values, what, 3);
  return {array.at(0), array.at(1), array.at(2)};
}

Quaternion to_quaternion(const py::handle& values, const char* what) {
  const auto array = finite_values(values, what, 4);
  return {array.at(0), array.at(1), array.at(2), array.at(3)};
}

py::array view(const double* first, std::size_t count, std::size_t stride, py::handle owner) {
  py::array array(py::dtype::of<double>(), {count}, {stride}, first, owner);
  py::detail::array_proxy(array.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return array;
}

std::int64_t deadline_after(double seconds, const char* what) {
  if (!(seconds >= 0.0 && seconds <= 1e6))
    throw py::value_error(std::string(what) + " takes 0 to 1e6 seconds");
  return monotonic_ns() + static_cast<std::int64_t>(seconds * 1e9);
}

namespace {

struct InterruptState {
  unsigned long main_thread = 0;  // PyThread_get_thread_ident() of Python's main thread
  std::int64_t next_look_ns = 0;
  std::exception_ptr error;
};

InterruptState& interrupts() {
  static InterruptState state;
  return state;
}

bool on_main_thread() noexcept {
  return PyThread_get_thread_ident() == interrupts().main_thread;
}

}  // namespace

bool SignalWatch::pending() noexcept {
  if (!on_main_thread() || !Py_IsInitialized()) return false;
  InterruptState& state = interrupts();
  if (state.error) return true;
  const std::int64_t now = monotonic_ns();
  if (now < state.next_look_ns) return false;
  state.next_look_ns = now + kLookEveryNs;
  try {
    py::gil_scoped_acquire acquire;
    if (PyErr_CheckSignals() == 0) return false;
    state.error = std::make_exception_ptr(py::error_already_set());
  } catch (...) {  // no memory to hold the Python error: raised as that instead
    state.error = std::current_exception();
  }
  return true;
}

void SignalWatch::raise_if_pending() {
  if (!on_main_thread()) return;
  if (std::exception_ptr error = std::exchange(interrupts().error, nullptr))
    std::rethrow_exception(error);
}

void watch_interrupts_in_waits() {
  interrupts().main_thread =
      py::module_::import("threading").attr("main_thread")().attr("ident").cast<unsigned long>();
  set_stop_source([]() noexcept { return SignalWatch().pending(); });
  // Not once the interpreter is going: a wait at exit (the hub client's) ends on its own.
  py::module_::import("atexit").attr("register")(
      py::cpp_function([] { set_stop_source(nullptr); }));
}

namespace {

// The hub's catalog, read in place; one reader per process.
CatalogReader& catalog_reader() {
  ensure_connected();
  static std::unique_ptr<CatalogReader> reader;
  if (!reader) {
    auto made = std::make_unique<CatalogReader>();
    made->wait(std::chrono::milliseconds(1000));
    reader = std::move(made);
  }
  return *reader;
}

py::dict entry_dict(const BodyList& list, std::uint32_t index) {
  const BodyInfo& info = list.bodies[index];
  py::dict entry;
  entry["channel"] = std::string(name_of(info.channel));
  entry["kind"] = info.kind == ChannelKind::kDevice ? "device" : "body";
  entry["owner"] = std::string(name_of(info.owner));
  entry["owner_pid"] = info.owner_pid;
  entry["publish_rate_hz"] = info.publish_rate_hz;
  const BodyEntry body = entry_of(list, index);
  entry["joint_names"] = body.joint_names;
  entry["sensor_rays"] = body.sensor_rays;
  entry["actuator_names"] = body.actuator_names;
  entry["child_names"] = body.child_names;
  entry["parent_name"] = body.parent_name;
  return entry;
}

py::dict percentiles_dict(const DurationPercentiles& p) {
  py::dict out;
  out["p50_us"] = p.p50_us;
  out["p99_us"] = p.p99_us;
  out["p999_us"] = p.p999_us;
  out["max_us"] = p.max_us;
  return out;
}

}  // namespace

py::dict loop_stats_dict(const LoopStats& stats) {
  py::dict out;
  out["name"] = std::string(name_of(stats.name));
  out["body"] = std::string(name_of(stats.body));
  out["pid"] = stats.header.publisher_pid;
  out["period_s"] = stats.period_s;
  out["rate_hz"] = stats.rate_hz;
  out["cycles"] = stats.cycles;
  out["overruns"] = stats.overruns;
  out["late_commands"] = stats.late_commands;
  out["wake_latency"] = percentiles_dict(stats.wake_latency);
  out["compute"] = percentiles_dict(stats.compute);
  out["realtime"] = stats.realtime != 0;
  out["memory_locked"] = stats.memory_locked != 0;
  out["lockstep"] = stats.lockstep != 0;
  out["cpu"] = stats.cpu;
  return out;
}

// The namespace of the world whose physics publishes `body` (BodyWorld), or none.
std::optional<std::string> world_namespace(const std::string& body, double wait_s) {
  const BodyEntry entry = wait_for_entry(body, wait_s, "body");
  const std::int64_t give_up = deadline_after(wait_s, "wait_s");
  std::optional<std::string> found;
  SignalWatch signals;
  {
    py::gil_scoped_release release;
    BodyClient client(entry);
    BodyWorld world(name_of(entry.info.channel));
    for (; !found && monotonic_ns() < give_up && !signals.pending() && !hub_lost();
         sleep_until_ns(monotonic_ns() + 2'000'000))
      if (const BodyState* state = client.latest_state())
        if (const std::string* name_space = world.name_space_of(*state)) found = *name_space;
  }
  signals.raise_if_pending();
  require_hub();
  return found;
}

}  // namespace afhub::python

PYBIND11_MODULE(afhub, module) {
  using namespace afhub::python;
  module.doc() =
      "afhub from Python: read bodies' states and write their commands in shared memory, "
      "control the world's clock, read and command devices, and run real-time loops.\n\n"
      "Every call joins the running hub on first use (afhub.connect() does it explicitly). "
      "Errors are afhub.Error with the command line's messages; a command the physics "
      "refused raises afhub.CommandRefused; bad arguments raise ValueError.";
  register_errors(module);
  watch_interrupts_in_waits();
  // pybind11 binds numpy's C API on first use, under a static guard that a thread
  // blocks on while holding the GIL: the importing thread does it now, before any other
  // thread (ambf_client's publisher) can race it into a deadlock.
  try {
    py::array_t<double> first_use(0);
  } catch (py::error_already_set&) {
    const auto executable = py::module_::import("sys").attr("executable").cast<std::string>();
    throw py::import_error("afhub needs numpy, which " + executable +
                           " cannot import: run Debian's /usr/bin/python3, with python3-numpy "
                           "installed (./run.sh build installs it)");
  }

  module.def(
      "connect", [](double wait_s) { ensure_connected(wait_s); }, py::arg("wait_s") = 0.0,
      "Joins the running hub (once per process), waiting up to wait_s seconds for it to "
      "come up. Raises afhub.Error saying how to start one when none runs.");
  module.def(
      "catalog",
      [] {
        afhub::CatalogReader& reader = catalog_reader();
        const afhub::BodyList& list = reader.latest();
        py::list entries;
        for (std::uint32_t i = 0; i < list.body_count; ++i) entries.append(entry_dict(list, i));
        return entries;
      },
      "Every live body and device as the hub lists it (`afhub ls`): a list of dicts with "
      "channel, kind ('body' or 'device'), owner, owner_pid, publish_rate_hz, "
      "joint_names (in state order), sensor_rays (per ray of the state's sensor arrays, its "
      "proximity sensor's name), actuator_names (in command order), child_names (bodies "
      "jointed directly below) and parent_name ('' for none); body names without their "
      "namespace, as in the model.");
  module.def(
      "bodies",
      [] {
        afhub::CatalogReader& reader = catalog_reader();
        const afhub::BodyList& list = reader.latest();
        std::vector<std::string> names;
        for (std::uint32_t i = 0; i < list.body_count; ++i)
          if (list.bodies[i].kind == afhub::ChannelKind::kBody)
            names.emplace_back(afhub::name_of(list.bodies[i].channel));
        return names;
      },
      "The channel names of the live bodies, e.g. ['afhub/arm/base', ...].");
  module.def(
      "resolve",
      [](const std::string& name) {
        require_no_nul(name);
        return std::string(afhub::name_of(catalog_reader().resolve(name).info.channel));
      },
      py::arg("name"),
      "The channel of the body or device named by `name`: its channel name or a unique "
      "suffix of it after a '/' ('arm/base', 'base'), as the command line finds them. "
      "Raises afhub.Error listing the candidates when none or several match.");
  module.def("world_namespace", &world_namespace, py::arg("body"), py::arg("wait_s") = 1.0,
             "The namespace of the world whose physics publishes `body` "
             "(World(namespace=...); '' for `afhub run` without --namespace), or None when none "
             "does within wait_s seconds.");
  module.def(
      "loop_stats",
      [] {
        ensure_connected();
        static afhub::LoopStatsReader reader;
        py::list out;
        for (const afhub::LoopStats& stats : reader.latest()) out.append(loop_stats_dict(stats));
        return out;
      },
      "The newest statistics of every live loop (what `afhub top` shows), one dict each: "
      "name, body, pid, period_s, rate_hz, cycles, overruns, late_commands, wake_latency and "
      "compute (p50_us, p99_us, p999_us, max_us), realtime, memory_locked, lockstep, cpu. A "
      "loop publishes once a second; one that just started may be missing.");

  register_body(module);
  register_device(module);
  register_world(module);
  register_loop(module);
}
