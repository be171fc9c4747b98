// afhub.Body and afhub.State: one body's newest state as numpy arrays, and its commands.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "afhub/hub/bodies.hpp"
#include "bindings.hpp"

namespace afhub::python {

// A body state copied out of shared memory at its real size: one small copy, so that its
// arrays stay valid for as long as Python holds them (a view on the held sample would
// change under them at the next read). It never changes: Body.read hands the same
// State again until a newer sample comes.
class State {
 public:
  explicit State(const BodyState& sample);
  const BodyState& operator*() const { return *state_; }
  const BodyState* operator->() const { return state_.get(); }
  // The joints' positions, velocities or efforts (`member`: the offset of that member
  // in JointSample) as a read-only numpy array, made on the first call. Side by side: a
  // contiguous array goes back into a command as is, where a view striding over the
  // samples is first copied.
  py::object joint_column(std::size_t member) const;

 private:
  // Shared with the arrays made on it (through a capsule, not this State: an array
  // holding its State while the State holds the array would never be freed).
  std::shared_ptr<BodyState> state_;
  mutable std::array<py::object, 3> columns_;
};

class Body {
 public:
  Body(const std::string& name, double wait_s);

  const std::string& channel() const { return channel_; }
  const std::vector<std::string>& joint_names() const { return entry_.joint_names; }
  // Its sensors, actuators and neighbours as the catalog names them (see BodyEntry).
  const BodyEntry& entry() const { return entry_; }
  std::size_t joint_index(const std::string& name) { return client_.joint_index(name); }
  // The newest state (a State), copied; the same object again while no newer sample
  // came; None before the first (after waiting up to wait_s for it).
  py::object read(double wait_s);
  // The first state of a step after `after_step` (or any newer sample when None),
  // waiting up to timeout_s; afhub.Error when none came.
  State wait_next(std::optional<std::uint64_t> after_step, double timeout_s);
  // Fills a command (joint_count joints, zeroed) with `fill` and publishes it, answering
  // the newest state; raises CommandRefused first when the physics refused an earlier one.
  template <class Fill>
  void send(std::uint32_t joint_count, const Fill& fill);
  // Raises CommandRefused when the physics refused a command of this process since the
  // last check.
  void check_refused();
  BodyClient& client() { return client_; }
  // Set by a lockstep afhub.Loop: its commands answer the step the loop is on.
  void set_lockstep(bool on) { lockstep_ = on; }

 private:
  BodyEntry entry_;
  std::string channel_;
  BodyClient client_;
  bool lockstep_ = false;
  std::uint32_t pid_;
  std::uint32_t refusals_seen_ = 0;
  bool refusals_known_ = false;
  std::int64_t first_command_ns_ = 0;  // monotonic_ns() when this body sent its first command
  py::object last_read_;               // the State read() returned last
  PayloadHeader last_read_header_{};   // and its sample's header, which tells a newer one
};

}  // namespace afhub::python
