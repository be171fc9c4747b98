// One body's two channels, from either side, and the body catalog.
//   BodyEntry: a catalog entry with its joint names, in this process's memory.
//   BodyPublisher (the physics side): publishes state, reads the command slot.
//   BodyClient (controllers, drivers, tools): reads state, writes commands.
//   DirectoryPublisher: the bodies a process owns, announced once for the catalog.
//   CatalogReader: every live body, as merged by the hub.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "afhub/hub/channel.hpp"
#include "afhub/shm_layout/body_command.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/catalog.hpp"

namespace afhub {

// How many bodies ahead a loop over many bodies' slots gives the prefetch hints below
// (BodyPublisher::prefetch_command, BodyClient::prefetch_state, ...): far enough for
// a body's lines to come while the bodies before it are read or written.
inline constexpr std::size_t kBodyPrefetchAhead = 4;

// The owner publishes state every period, paused or not, into the body's state slot
// (see channel.hpp); a reader that joins gets the current state at once.
class BodyPublisher {
 public:
  explicit BodyPublisher(std::string_view body_channel);

  // A default state of `joints` joints (joint_count set) in shared memory, loaned at
  // its real size (body_state_bytes), or nullptr when memory is exhausted.
  BodyState* loan_state(std::uint32_t joints) noexcept {
    BodyState* state = state_.loan(body_state_bytes(joints));
    if (state) state->joint_count = joints;
    return state;
  }
  // As loan_state, but keeping the fields of the last update (defaults the first time):
  // for the physics, which sets every field at every step.
  BodyState* rewrite_state(std::uint32_t joints) noexcept {
    BodyState* state = state_.loan_rewritten(body_state_bytes(joints));
    if (state) state->joint_count = joints;
    return state;
  }
  void publish_state(BodyState* state) noexcept { state_.publish(state); }
  void publish_state(BodyState* state, std::int64_t stamp_ns) noexcept {
    state_.publish(state, stamp_ns);
  }
  bool has_state_readers() const noexcept { return state_.raw().has_readers(); }
  // Hints for a loop over many bodies, a few bodies ahead (RawWriter::prefetch_update,
  // RawLatestReader::prefetch).
  // A physics' step, of a body with `rays` sensor rays: the lines it writes every step
  // (SimChannels::publish_state). Not those of the rays' ranges and the last refused
  // command, rewritten only when they change, which the readers then keep in their
  // caches.
  void prefetch_state_update(std::uint32_t rays) const noexcept {
    constexpr std::uint32_t distances = offsetof(BodyState, sensor_distances_m);
    state_.raw().prefetch_update(
        {{0, offsetof(BodyState, refused_command_pid)},
         {distances, distances + rays * static_cast<std::uint32_t>(sizeof(double))},
         {offsetof(BodyState, joints), UINT32_MAX}});
  }
  void prefetch_command() const noexcept { command_.raw().prefetch(); }
  // The newest command, or nullptr before the first: this process's checked copy of
  // its slot, valid and unchanged until the next call.
  const BodyCommand* latest_command() noexcept { return command_.latest(); }
  bool command_updated() const { return command_.updated(); }
  std::uint32_t command_bytes() { return command_.raw().latest_bytes(); }
  std::uint64_t refused_commands() { return command_.raw().refused_count(); }
  // The command reader, to wait on (SampleWaiter).
  RawLatestReader& command_reader() noexcept { return command_.raw(); }
  const std::string& channel() const { return channel_; }

 private:
  std::string channel_;
  Writer<BodyState> state_;
  LatestReader<BodyCommand> command_;
};

// A body as the catalog lists it, with its joint names in state order and the names
// of its parts and neighbours (see BodyInfo).
struct BodyEntry {
  BodyInfo info;
  std::vector<std::string> joint_names;
  std::vector<std::string> sensor_rays{};     // per ray of its state, its sensor's name
  std::vector<std::string> actuator_names{};  // in command order
  std::vector<std::string> child_names{};     // bodies jointed directly below it
  std::string parent_name{};                  // "" when it has none
};

class BodyClient {
 public:
  // `body_channel` is a full channel name as listed in the catalog.
  explicit BodyClient(std::string_view body_channel);
  // From the body's catalog entry (CatalogReader::resolve): its joint names come along.
  explicit BodyClient(const BodyEntry& entry);

  // The body's joint names, in the order of its state's and command's joint arrays.
  // Constructed from a channel name, the client looks them up in the catalog on the
  // first call (not real-time safe: call it before the loop).
  const std::vector<std::string>& joint_names();
  // The index of joint `name` in the body's state and command, e.g.
  //   command.joints[body.joint_index("link1-link2")].value = 0.3;
  // Throws afhub::Error listing the body's joint names when it has no such joint.
  std::size_t joint_index(std::string_view name);

  // The newest state, or nullptr before the first: this process's checked copy of
  // its slot, valid and unchanged until the next call.
  const BodyState* latest_state() noexcept { return state_.latest(); }
  bool state_updated() const { return state_.updated(); }
  // Connected to the owner's state channel: every state published from now on arrives.
  bool subscribed() { return state_.raw().subscribed(); }
  std::uint64_t refused_states() { return state_.raw().refused_count(); }
  // The state reader, to wait on (SampleWaiter).
  RawLatestReader& state_reader() noexcept { return state_.raw(); }
  // A default command of `joints` joint commands (joint_count set) in shared memory,
  // loaned at its real size (body_command_bytes), to fill, then publish_command().
  BodyCommand* loan_command(std::uint32_t joints) noexcept {
    BodyCommand* command = command_.loan(body_command_bytes(joints));
    if (command) command->joint_count = joints;
    return command;
  }
  void publish_command(BodyCommand* command) noexcept { command_.publish(command); }
  // Hints for a loop over many bodies, a few bodies ahead (as BodyPublisher's).
  void prefetch_state() const noexcept { state_.raw().prefetch(); }
  void prefetch_command_update() const noexcept { command_.raw().prefetch_update(); }
  // A reader (the physics, once it has found this writer's slot) holds the command slot.
  bool command_has_readers() const noexcept { return command_.raw().has_readers(); }
  const std::string& channel() const { return channel_; }

 private:
  std::string channel_;
  LatestReader<BodyState> state_;
  Writer<BodyCommand> command_;
  std::vector<std::string> joint_names_;
  bool joint_names_known_ = false;
};

// The joint names of `body`, an entry of `list` (checked by check_payload), in state order.
std::vector<std::string> joint_names_of(const BodyList& list, const BodyInfo& body);
// Entry `index` of `list` with its joint names.
BodyEntry entry_of(const BodyList& list, std::uint32_t index);

// A catalog entry for a body this process owns; throws afhub::Error on a bad name.
BodyEntry make_body_entry(std::string_view body_channel,
                          const std::vector<std::string>& joint_names);

// Adds the names of a body's parts and neighbours to its entry (see BodyEntry);
// throws afhub::Error when there are more than a state or command carries, or a name
// is too long for the catalog.
void set_body_parts(BodyEntry& entry, std::vector<std::string> sensor_rays,
                    std::vector<std::string> actuator_names, std::vector<std::string> child_names,
                    std::string parent_name);

// A catalog entry for a device this process drives ("device/<name>": DeviceState
// and DeviceCommand); throws afhub::Error on a bad name.
BodyEntry make_device_entry(std::string_view device_name);
// A BodyList of `entries` loaned from `writer` at its real size (body_list_bytes),
// each distinct joint name once; nullptr when shared memory is exhausted or the
// entries exceed a catalog's capacity. Not real-time safe.
BodyList* loan_body_list(RawWriter& writer, const std::vector<BodyEntry>& entries);

class DirectoryPublisher {
 public:
  // On {"afhub", "<runtime name>/<n>", "directory"}, n counting the publishers of this
  // process (each its own channel: the hub keeps one sample per channel). Needs
  // connect_to_hub().
  DirectoryPublisher();
  // Announces a body; publish() sends the directory.
  void add(const BodyEntry& body);
  void publish();

 private:
  std::vector<BodyEntry> bodies_;
  RawWriter writer_;
};

class CatalogReader {
 public:
  CatalogReader();
  // Waits up to `timeout` for the hub's catalog. Throws afhub::Error if none comes,
  // saying why: no room for another reader (kMaxReadersPerChannel), or a hub silent.
  void wait(std::chrono::milliseconds timeout);
  // The newest catalog (after wait()); read in place.
  const BodyList& latest() noexcept;
  std::vector<std::string> channels() noexcept(false);
  // Resolves an exact name or unique suffix; throws afhub::Error listing candidates.
  BodyEntry resolve(std::string_view query);

 private:
  RawLatestReader reader_;
  const BodyList* current_ = nullptr;
};

// The catalog entry for `query` (see CatalogReader::resolve). A process started with
// the physics that owns the body, or re-attached to a hub before it, waits for it
// until `give_up_ns` (CLOCK_MONOTONIC; INT64_MAX: until it comes), saying so once on
// stderr as `who` (of a `kind`: "body", "device"). Throws afhub::Error when it is still
// missing then (adding `hint` to the message when it waited), on Ctrl-C, or once the hub
// is lost.
BodyEntry wait_for_body(const std::string& query, const std::string& who, std::int64_t give_up_ns,
                        const std::string& hint = "", const char* kind = "body");

// Whether `channel`, or its end after one of its '/', matches one of `globs` (fnmatch
// patterns: '*' crosses '/'), as the options that choose bodies (`afhub record --bodies`,
// the DDS bridge's `bodies`) take them: "arm/base" and "base" choose "afhub/arm/base", as
// the command line names bodies.
bool matches_any(const std::string& channel, const std::vector<std::string>& globs);

// Writes `text` into a fixed name buffer, cut to fit, NUL-terminated.
template <std::size_t N>
void set_name(std::array<char, N>& buffer, std::string_view text) noexcept {
  const std::size_t length = std::min(text.size(), N - 1);
  std::copy_n(text.data(), length, buffer.data());
  buffer[length] = '\0';
}

// Text of a fixed NUL-terminated name buffer.
template <std::size_t N>
std::string_view name_of(const std::array<char, N>& buffer) {
  std::size_t length = 0;
  while (length < N && buffer[length] != '\0') ++length;
  return {buffer.data(), length};
}

}  // namespace afhub
