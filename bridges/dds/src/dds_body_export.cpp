// Local bodies out over DDS, and commands to them in (see dds_body_export.hpp).
#include "dds_body_export.hpp"

#include <algorithm>
#include <array>
#include <cstdio>

#include "afhub/hub/hub_loss.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"
#include "dds_convert.hpp"

namespace afhub::bridges {

BodyExport::BodyExport(dds_entity_t participant, const BodyTopics& topics,
                       const DdsBridgeOptions& options, SampleWaiter& arrivals)
    : options_(options), arrivals_(arrivals) {
  if (options.profile == "ros2")
    ros2_ = std::make_unique<Ros2Profile>(participant, options.ros2_prefix, options.accept_commands,
                                          options.max_command_age_s);
  const Qos stream, info;
  set_stream_qos(stream.get(), options.reliable);
  set_ignore_own(stream.get());
  set_info_qos(info.get());
  set_ignore_own(info.get());
  state_writer_ = Entity(dds_create_writer(participant, topics.state.id(), stream.get(), nullptr),
                         "state writer");
  info_writer_ =
      Entity(dds_create_writer(participant, topics.info.id(), info.get(), nullptr), "info writer");
  make_state_sample(state_out_);
  make_command_sample(command_in_);
  if (options.accept_commands) {
    command_reader_ =
        Entity(dds_create_reader(participant, topics.command.id(), stream.get(), nullptr),
               "command reader");
    listen(command_reader_.id(), on_commands, this);
  }
}

BodyExport::~BodyExport() {
  stop_listening(command_reader_.id());
  ros2_.reset();  // before the state readers its bodies point to
  free_state_sample(state_out_);
  free_command_sample(command_in_);
}

ExportCounters BodyExport::counters() const {
  const std::lock_guard lock(mutex_);
  return counters_;
}

BodyExport::Body* BodyExport::find(const char* channel) noexcept {
  for (Body& body : exported_)
    if (body.channel == channel) return &body;
  return nullptr;
}

// A body whose state reader finds no iceoryx subscriber port left is not exported,
// said once; the next scan tries again (after the first refusal, a scan tries no more).
void BodyExport::scan(const BodyList& catalog,
                      const std::function<bool(std::string_view)>& mirrored) {
  std::string refusal;
  for (std::uint32_t i = 0; i < catalog.body_count; ++i) {
    const std::string channel(name_of(catalog.bodies[i].channel));
    if (catalog.bodies[i].kind != ChannelKind::kBody ||
        !matches_any(channel, options_.body_globs) || mirrored(channel) || find(channel.c_str()))
      continue;
    Body body{channel, nullptr, nullptr};
    if (refusal.empty()) {
      try {
        body.state = std::make_unique<LatestReader<BodyState>>(body_state_channel(channel));
      } catch (const Error& error) {
        refusal = error.what();
      }
    } else if (refusal.find("(as for ") == std::string::npos) {
      refusal = "no iceoryx subscriber port left (as for the body above)";
    }
    if (!body.state) {
      if (not_exported_.insert(channel).second)
        std::fprintf(stderr, "afhub bridge dds: not exporting %s (tried again each second): %s\n",
                     channel.c_str(), refusal.c_str());
      continue;
    }
    if (not_exported_.erase(channel))
      std::fprintf(stderr, "afhub bridge dds: exporting %s now\n", channel.c_str());
    arrivals_.attach(body.state->raw());  // when full: by the cycle alone
    const BodyEntry entry = entry_of(catalog, i);
    if (ros2_) ros2_->add_body(channel, entry.joint_names, *body.state);
    {
      const std::lock_guard lock(mutex_);
      exported_.push_back(std::move(body));
    }
    announce(channel, entry.joint_names);
  }
}

// A body's joint names, once, for mirrors (transient local: late ones too).
void BodyExport::announce(const std::string& channel, const std::vector<std::string>& joint_names) {
  afhub_dds_BodyInfo info{};
  std::snprintf(info.body, sizeof info.body, "%s", channel.c_str());
  std::vector<std::array<char, 64>> names(joint_names.size());
  for (std::size_t j = 0; j < joint_names.size(); ++j) set_name(names[j], joint_names[j]);
  info.joint_names._buffer = reinterpret_cast<char(*)[64]>(names.data());
  info.joint_names._length = info.joint_names._maximum = static_cast<std::uint32_t>(names.size());
  info.joint_names._release = false;
  checked(dds_write(info_writer_.id(), &info), "writing a body's info");
  std::fprintf(stderr, "afhub bridge dds: exporting %s (%zu joints)\n", channel.c_str(),
               joint_names.size());
}

void BodyExport::export_states() noexcept {
  const std::int64_t now_ns = options_.body_rate_hz > 0.0 ? monotonic_ns() : 0;
  for (std::size_t i = 0; i < exported_.size(); ++i) {
    Body& body = exported_[i];
    const BodyState* state = body.state->latest();
    if (!state || !body.state->updated()) continue;
    if (options_.body_rate_hz > 0.0) {  // newest wins: the states in between stay here
      if (static_cast<double>(now_ns - body.last_out_ns) < 1e9 / options_.body_rate_hz) continue;
      body.last_out_ns = now_ns;
    }
    to_dds(body.channel, *state, state_out_);
    if (dds_write(state_writer_.id(), &state_out_) >= 0) ++counters_.states_out;
    if (ros2_) ros2_->publish(i, *state);
  }
}

void BodyExport::import_ros2_commands() noexcept {
  if (ros2_ && options_.accept_commands) ros2_->import_commands();
}

// On Cyclone's receive thread, so that a command never waits for the bridge's loop.
void BodyExport::on_commands(dds_entity_t, void* self) {
  auto* exporter = static_cast<BodyExport*>(self);
  const std::lock_guard lock(exporter->mutex_);
  exporter->import_commands();
}

// A command older than the bound by its DDS source timestamp is dropped, never
// applied late. Once the hub is lost, none goes into its memory: the process is
// about to re-attach (hub_loss.hpp), and the sender's next commands come then.
void BodyExport::import_commands() {
  void* samples[1] = {&command_in_};
  dds_sample_info_t info;
  const auto max_age_ns = static_cast<std::int64_t>(options_.max_command_age_s * 1e9);
  while (!hub_lost() && dds_take(command_reader_.id(), samples, &info, 1, 1) > 0) {
    if (!info.valid_data) continue;
    const std::int64_t age_ns = dds_time() - info.source_timestamp;
    if (age_ns > max_age_ns) {
      ++counters_.stale_commands;
      continue;
    }
    if (options_.latency) command_ages_.record(age_ns);
    Body* body = find(command_in_.body);
    if (!body) {
      ++counters_.unknown_bodies;
      continue;
    }
    if (!valid_dds_command(command_in_)) {
      ++counters_.bad_commands;
      continue;
    }
    if (!body->command && !open_command_writer(*body)) continue;
    const std::uint32_t joints =
        std::min<std::uint32_t>(command_in_.joints._length, kMaxJointsPerBody);
    BodyCommand* command = body->command->loan(body_command_bytes(joints));
    if (!command) continue;
    command->joint_count = joints;
    from_dds(command_in_, *command);
    body->command->publish(command);
    ++counters_.commands_in;
  }
}

// False (said once) when iceoryx has no publisher port left for it.
bool BodyExport::open_command_writer(Body& body) {
  try {
    body.command = std::make_unique<Writer<BodyCommand>>(body_command_channel(body.channel));
    return true;
  } catch (const Error& error) {
    ++counters_.bad_commands;
    if (!body.command_refused)
      std::fprintf(stderr, "afhub bridge dds: no commands for %s: %s\n", body.channel.c_str(),
                   error.what());
    body.command_refused = true;
    return false;
  }
}

void BodyExport::report() const {
  if (ros2_) ros2_->report();
  const std::lock_guard lock(mutex_);
  if (options_.latency && command_ages_.count() > 0)
    std::fprintf(stderr,
                 "afhub bridge dds: applied command age (the commander's publish to applied "
                 "here, by the DDS source timestamp, %llu commands): p50 %.1f us, p99 %.1f us, "
                 "max %.1f us\n",
                 static_cast<unsigned long long>(command_ages_.count()),
                 command_ages_.percentile_us(0.5), command_ages_.percentile_us(0.99),
                 command_ages_.max_us());
}

}  // namespace afhub::bridges
