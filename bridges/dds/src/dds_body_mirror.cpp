// Remote bodies into this hub (see dds_body_mirror.hpp).
#include "dds_body_mirror.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

#include "afhub/hub/body_claims.hpp"
#include "afhub/hub/hub_health.hpp"
#include "afhub/hub/hub_loss.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/shm_layout/error.hpp"
#include "dds_convert.hpp"

namespace afhub::bridges {
namespace {

// A name from the network, which may lack its NUL.
template <std::size_t N>
std::string_view text_of(const char (&name)[N]) noexcept {
  return {name, strnlen(name, N)};
}

}  // namespace

BodyMirror::BodyMirror(dds_entity_t participant, const BodyTopics& topics,
                       const DdsBridgeOptions& options, SampleWaiter& arrivals,
                       MirrorDirectory& directory, MirrorClaims& claims)
    : options_(options), arrivals_(arrivals), directory_(directory), claims_(claims) {
  const Qos stream, info;
  set_stream_qos(stream.get(), options.reliable);
  set_ignore_own(stream.get());
  set_info_qos(info.get());
  set_ignore_own(info.get());
  info_reader_ =
      Entity(dds_create_reader(participant, topics.info.id(), info.get(), nullptr), "info reader");
  command_writer_ = Entity(
      dds_create_writer(participant, topics.command.id(), stream.get(), nullptr), "command writer");
  make_state_sample(state_in_);
  make_command_sample(command_out_);
  state_reader_ = Entity(dds_create_reader(participant, topics.state.id(), stream.get(), nullptr),
                         "state reader");
  listen(state_reader_.id(), on_states, this);
}

BodyMirror::~BodyMirror() {
  stop_listening(state_reader_.id());
  free_state_sample(state_in_);
  free_command_sample(command_out_);
}

MirrorCounters BodyMirror::counters() const {
  const std::lock_guard lock(mutex_);
  return counters_;
}

bool BodyMirror::mirrors(std::string_view channel) const noexcept {
  for (const Body& body : mirrored_)
    if (body.channel == channel) return true;
  return false;
}

BodyMirror::Body* BodyMirror::find(std::string_view channel) noexcept {
  for (Body& body : mirrored_)
    if (body.channel == channel) return &body;
  return nullptr;
}

// Announcements are taken only while a claim can be queued: the others wait in the
// reader until there is room.
void BodyMirror::take_announcements() {
  void* samples[1] = {nullptr};  // loaned from the reader: joint name lists vary
  dds_sample_info_t info;
  while (claims_.has_room() && dds_take(info_reader_.id(), samples, &info, 1, 1) > 0) {
    const auto* body_info = static_cast<const afhub_dds_BodyInfo*>(samples[0]);
    const std::string_view channel = text_of(body_info->body);
    if (info.valid_data && matches_any(std::string(channel), options_.body_globs) &&
        !find(channel) && claims_.may_ask(channel))
      ask(*body_info);
    dds_return_loan(info_reader_.id(), samples, 1);
    samples[0] = nullptr;
  }
}

void BodyMirror::ask(const afhub_dds_BodyInfo& info) {
  const std::string channel(text_of(info.body));
  const std::uint32_t joints = info.joint_names._length;
  std::vector<std::string> joint_names;
  if (joints <= kMaxJointsPerBody)
    for (std::uint32_t j = 0; j < joints; ++j)
      joint_names.emplace_back(text_of(info.joint_names._buffer[j]));
  claims_.ask(channel,
              [this, channel, joints, joint_names] { return claim(channel, joints, joint_names); });
}

// On the claims' thread. A body that does not fit (too many joints for a state, too
// many bodies for this hub, or a directory larger than its chunks) is refused.
MirrorClaims::Install BodyMirror::claim(const std::string& channel, std::uint32_t announced_joints,
                                        const std::vector<std::string>& joint_names) {
  if (announced_joints > kMaxJointsPerBody)
    throw Error("it has " + std::to_string(announced_joints) +
                " joints; a body state holds at most " + std::to_string(kMaxJointsPerBody));
  const BodyEntry entry = make_body_entry(channel, joint_names);
  directory_.check_room(entry);
  check_room_for_bodies({channel}, 1);
  require_chunks({written_as_slot(body_state_bytes(announced_joints))}, "mirroring " + channel);
  auto body = std::make_shared<Body>(
      Body{channel, announced_joints, std::make_unique<BodyPublisher>(channel)});
  directory_.add(entry);
  return [this, body] { install(std::move(*body)); };
}

// On the loop's thread, which owns the waiter and is the one that grows the bodies.
void BodyMirror::install(Body body) {
  arrivals_.attach(body.publisher->command_reader());  // when full: by the cycle alone
  {
    const std::lock_guard lock(mutex_);
    mirrored_.push_back(std::move(body));
  }
  std::fprintf(stderr, "afhub bridge dds: mirroring %s (%u joints)\n",
               mirrored_.back().channel.c_str(), static_cast<unsigned>(mirrored_.back().joints));
}

// On Cyclone's receive thread, so that a state never waits for the bridge's loop.
void BodyMirror::on_states(dds_entity_t, void* self) {
  auto* mirror = static_cast<BodyMirror*>(self);
  const std::lock_guard lock(mirror->mutex_);
  mirror->mirror_states();
}

// Once the hub is lost, nothing goes into its memory: the process is about to
// re-attach (hub_loss.hpp), and the next states go into the next hub.
void BodyMirror::mirror_states() {
  void* samples[1] = {&state_in_};
  dds_sample_info_t info;
  while (!hub_lost() && dds_take(state_reader_.id(), samples, &info, 1, 1) > 0) {
    if (!info.valid_data) continue;
    Body* body = find(text_of(state_in_.body));
    if (!body) {  // being claimed (counted), its info has not come yet, or it was refused
      claims_.drop_if_pending(text_of(state_in_.body));
      continue;
    }
    BodyState* state = body->publisher->loan_state(body->joints);
    if (!state) continue;
    from_dds(state_in_, *state);
    body->publisher->publish_state(state);
    if (options_.latency) state_ages_.record(monotonic_ns() - state_in_.header.source_stamp_ns);
    ++counters_.states_in;
  }
}

// The DDS source timestamp is when the local controller published.
void BodyMirror::export_commands() noexcept {
  for (Body& body : mirrored_) {
    const BodyCommand* command = body.publisher->latest_command();
    if (!command || !body.publisher->command_updated()) continue;
    to_dds(body.channel, *command, command_out_);
    const std::int64_t age_ns =
        std::max<std::int64_t>(0, monotonic_ns() - command->header.publish_stamp_ns);
    if (dds_write_ts(command_writer_.id(), &command_out_, dds_time() - age_ns) >= 0)
      ++counters_.commands_out;
  }
}

void BodyMirror::report() const {
  const std::lock_guard lock(mutex_);
  if (options_.latency && state_ages_.count() > 0)
    std::fprintf(stderr,
                 "afhub bridge dds: mirrored state age (source publish to publish here, "
                 "%llu states): p50 %.1f us, p99 %.1f us, max %.1f us\n",
                 static_cast<unsigned long long>(state_ages_.count()),
                 state_ages_.percentile_us(0.5), state_ages_.percentile_us(0.99),
                 state_ages_.max_us());
}

}  // namespace afhub::bridges
