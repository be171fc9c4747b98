// `afhub bridge dds` (see dds_bridge.hpp): one loop at --rate that exports local
// bodies and mirrors remote ones. In steady state nothing here allocates: samples are
// made once with full-capacity sequences, bodies are looked up in vectors made when
// they appear, and the catalog is rescanned for new bodies once a second (which may
// allocate; it is not per message).
#include "afhub/bridges/dds_bridge.hpp"

#include <dds/dds.h>
#include <fnmatch.h>
#include <sched.h>
#include <signal.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <memory>
#include <mutex>
#include <set>

#include "afhub/bridges/dds_bridge_config.hpp"
#include "afhub/hub/bodies.hpp"
#include "afhub/hub/body_claims.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/sample_waiter.hpp"
#include "afhub/hub/stop_signal.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/rt/cpu_wake_latency.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"
#include "age_histogram.hpp"
#include "dds_convert.hpp"
#include "dds_device_world.hpp"
#include "dds_security.hpp"
#include "ros2_profile.hpp"

namespace afhub::bridges {
namespace {

constexpr const char* kStateTopic = "afhub/body_state";
constexpr const char* kCommandTopic = "afhub/body_command";
constexpr const char* kInfoTopic = "afhub/body_info";

void check(dds_return_t result, const char* what) {
  if (result < 0)
    throw Error(std::string("DDS: ") + what + ": " + dds_strretcode(result) +
                " (check CYCLONEDDS_URI and the --domain)");
}

// A DDS entity deleted with its owner.
struct Entity {
  dds_entity_t id = 0;
  Entity() = default;
  Entity(dds_entity_t entity, const char* what) : id(entity) { check(entity, what); }
  Entity(const Entity&) = delete;
  Entity& operator=(const Entity&) = delete;
  ~Entity() {
    if (id > 0) dds_delete(id);
  }
};

struct Qos {
  dds_qos_t* qos = dds_create_qos();
  ~Qos() { dds_delete_qos(qos); }
};

// States and commands: newest wins (keep last 1 per body); best effort unless asked.
void set_stream_qos(dds_qos_t* qos, bool reliable) {
  if (reliable)
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  else
    dds_qset_reliability(qos, DDS_RELIABILITY_BEST_EFFORT, 0);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
}

// Joint names: reliable and transient local, so a late mirror learns every body.
void set_info_qos(dds_qos_t* qos) {
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(qos, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
}

// SIGUSR1: print the counters now (tests read them at a moment they choose).
volatile sig_atomic_t report_requested = 0;
void request_report(int) {
  report_requested = 1;
}

struct Counters {
  std::uint64_t states_out = 0, states_in = 0, commands_out = 0, commands_in = 0;
  std::uint64_t stale_commands = 0, bad_commands = 0, unknown_bodies = 0;
};

// A local body whose state goes out. Its command writer is made at the first network
// command: a writer takes one of iceoryx's 512 publisher ports, and an exporter of
// hundreds of bodies that takes no commands must not take hundreds of ports.
struct ExportedBody {
  std::string channel;
  std::unique_ptr<LatestReader<BodyState>> state;
  std::unique_ptr<Writer<BodyCommand>> command;
  bool command_refused = false;
  std::int64_t last_out_ns = 0;  // for --body-rate
};

// A remote body published into this hub.
struct MirroredBody {
  std::string channel;
  std::uint32_t joints = 0;
  std::unique_ptr<BodyPublisher> publisher;
};

class Bridge {
 public:
  explicit Bridge(const DdsBridgeOptions& options) : options_(options) {
    if (!options.interface.empty())
      domain_ = make(dds_create_domain(options.domain, interface_config(options.interface).c_str()),
                     "binding the domain to the --interface");
    Qos participant;
    if (!options.security_dir.empty())
      add_security_properties(participant.qos, options.security_dir);
    participant_ = std::make_unique<Entity>(
        dds_create_participant(options.domain, participant.qos, nullptr),
        options.security_dir.empty()
            ? "creating the participant"
            : "creating a secure participant (are the --security files valid: the "
              "certificate signed by identity_ca.pem, the .p7s signed by permissions_ca.pem?)");
    const dds_entity_t p = participant_->id;
    if (options.profile == "ros2" && options.export_bodies)
      ros2_ = std::make_unique<Ros2Profile>(p, options.ros2_prefix, options.accept_commands,
                                            options.max_command_age_s);
    state_topic_ = std::make_unique<Entity>(
        dds_create_topic(p, &afhub_dds_BodyState_desc, kStateTopic, nullptr, nullptr),
        "creating the state topic");
    command_topic_ = std::make_unique<Entity>(
        dds_create_topic(p, &afhub_dds_BodyCommand_desc, kCommandTopic, nullptr, nullptr),
        "creating the command topic");
    info_topic_ = std::make_unique<Entity>(
        dds_create_topic(p, &afhub_dds_BodyInfo_desc, kInfoTopic, nullptr, nullptr),
        "creating the body info topic");
    Qos stream, info;
    set_stream_qos(stream.qos, options.reliable);
    set_info_qos(info.qos);
    // This bridge's own samples never come back to it (export and mirror in one process).
    dds_qset_ignorelocal(stream.qos, DDS_IGNORELOCAL_PARTICIPANT);
    dds_qset_ignorelocal(info.qos, DDS_IGNORELOCAL_PARTICIPANT);
    if (options.export_bodies) {
      state_writer_ =
          make(dds_create_writer(p, state_topic_->id, stream.qos, nullptr), "state writer");
      info_writer_ = make(dds_create_writer(p, info_topic_->id, info.qos, nullptr), "info writer");
      if (options.accept_commands)
        command_reader_ =
            make(dds_create_reader(p, command_topic_->id, stream.qos, nullptr), "command reader");
    }
    if (options.mirror) {
      state_reader_ =
          make(dds_create_reader(p, state_topic_->id, stream.qos, nullptr), "state reader");
      info_reader_ = make(dds_create_reader(p, info_topic_->id, info.qos, nullptr), "info reader");
      command_writer_ =
          make(dds_create_writer(p, command_topic_->id, stream.qos, nullptr), "command writer");
      directory_ = std::make_unique<DirectoryPublisher>();
    }
    devices_and_world_ = std::make_unique<DeviceWorldBridge>(p, options, directory_.get());
    for (afhub_dds_BodyState* sample : {&state_out_, &state_in_}) make_state_sample(*sample);
    for (afhub_dds_BodyCommand* sample : {&command_out_, &command_in_})
      make_command_sample(*sample);
    if (command_reader_) forward_on_data(command_reader_->id);
    if (state_reader_) forward_on_data(state_reader_->id);
  }

  ~Bridge() {
    // Returns once a running callback is done: none touches this bridge after this.
    if (command_reader_) dds_set_listener(command_reader_->id, nullptr);
    if (state_reader_) dds_set_listener(state_reader_->id, nullptr);
    for (afhub_dds_BodyState* sample : {&state_out_, &state_in_}) free_state_sample(*sample);
    for (afhub_dds_BodyCommand* sample : {&command_out_, &command_in_})
      free_command_sample(*sample);
  }

  Bridge(const Bridge&) = delete;
  Bridge& operator=(const Bridge&) = delete;

  int run() {
    std::unique_ptr<CatalogReader> catalog;
    if (options_.export_bodies) {
      catalog = std::make_unique<CatalogReader>();
      catalog->wait(std::chrono::milliseconds(2000));
    }
    const auto period_ns = static_cast<std::int64_t>(1e9 / options_.rate_hz);
    const std::int64_t start_ns = monotonic_ns();
    std::int64_t next_ns = start_ns, next_scan_ns = start_ns,
                 next_report_ns = start_ns + 5'000'000'000;
    while (!stop_requested()) {
      const std::int64_t now_ns = monotonic_ns();
      {
        const std::lock_guard lock(mutex_);  // exported_ and mirrored_ grow here
        if (catalog && now_ns >= next_scan_ns) {
          scan_catalog(*catalog);
          devices_and_world_->scan(catalog->latest());
          next_scan_ns = now_ns + 1'000'000'000;
        }
        if (options_.mirror) mirror_infos();
        if (now_ns >= next_report_ns || report_requested) {
          report_requested = 0;
          report();
          next_report_ns = now_ns + 5'000'000'000;
        }
      }
      forward_local();
      if (options_.seconds > 0.0 &&
          static_cast<double>(now_ns - start_ns) * 1e-9 >= options_.seconds)
        break;
      next_ns += period_ns;
      if (next_ns < now_ns) next_ns = now_ns;  // after a stall: no burst of catch-up cycles
      wait_until(next_ns);
    }
    const std::lock_guard lock(mutex_);
    report();
    return 0;
  }

 private:
  // Until `deadline_ns`, forwarding local states and commands to mirrored bodies as they
  // come: they wake the iceoryx WaitSet (or, with spin, are polled for). DDS states and
  // commands never wait for this loop: Cyclone's thread that receives them publishes
  // them into the hub (on_data), as raw DDS would wake a reader.
  void wait_until(std::int64_t deadline_ns) {
    for (std::int64_t now_ns = monotonic_ns(); now_ns < deadline_ns && !stop_requested();
         now_ns = monotonic_ns()) {
      if (options_.spin)
        sched_yield();
      else
        state_arrival_.wait(deadline_ns - now_ns);
      forward_local();
    }
  }

  // This hub's side, on the loop's thread and without the mutex (so that on_data never
  // waits for a DDS write here): exported states, commands written to mirrored bodies,
  // and the inputs polled rather than heard (ROS 2 commands, devices, the world).
  // exported_ and mirrored_ only grow on this thread.
  void forward_local() {
    if (options_.export_bodies) {
      export_states();
      devices_and_world_->export_states(monotonic_ns());
      if (options_.accept_commands) {
        if (ros2_) ros2_->import_commands();
        devices_and_world_->import_commands();
      }
    }
    if (options_.mirror) {
      export_mirrored_commands();
      devices_and_world_->mirror();
    }
  }

  // In Cyclone's receive thread, under the mutex that the loop holds while the bodies
  // change. Touches only what the loop's forward_local() does not write (a body's
  // command writer, its publisher's state side, the incoming samples and counters).
  static void on_data(dds_entity_t reader, void* self) {
    auto* bridge = static_cast<Bridge*>(self);
    const std::lock_guard lock(bridge->mutex_);
    if (bridge->command_reader_ && reader == bridge->command_reader_->id) bridge->import_commands();
    if (bridge->state_reader_ && reader == bridge->state_reader_->id) bridge->mirror_states();
  }

  void forward_on_data(dds_entity_t reader) {
    dds_listener_t* listener = dds_create_listener(this);
    dds_lset_data_available(listener, on_data);
    const dds_return_t result = dds_set_listener(reader, listener);
    dds_delete_listener(listener);
    check(result, "setting a reader's listener");
  }

  static std::unique_ptr<Entity> make(dds_entity_t entity, const char* what) {
    return std::make_unique<Entity>(entity, what);
  }

  void report() {
    std::fprintf(stderr,
                 "afhub bridge dds: exported %zu bodies, mirrored %zu; states out %llu in %llu, "
                 "commands out %llu in %llu, stale commands dropped %llu, bad %llu\n",
                 exported_.size(), mirrored_.size(),
                 static_cast<unsigned long long>(counters_.states_out),
                 static_cast<unsigned long long>(counters_.states_in),
                 static_cast<unsigned long long>(counters_.commands_out),
                 static_cast<unsigned long long>(counters_.commands_in),
                 static_cast<unsigned long long>(counters_.stale_commands),
                 static_cast<unsigned long long>(counters_.bad_commands));
    if (ros2_) ros2_->report();
    const DeviceWorldCounters& extra = devices_and_world_->counters();
    if (!options_.device_globs.empty() || options_.world)
      std::fprintf(stderr,
                   "afhub bridge dds: devices exported %zu, mirrored %zu; device and world "
                   "samples out %llu in %llu, commands out %llu in %llu, stale dropped %llu, "
                   "bad %llu\n",
                   devices_and_world_->exported_devices(), devices_and_world_->mirrored_devices(),
                   static_cast<unsigned long long>(extra.states_out),
                   static_cast<unsigned long long>(extra.states_in),
                   static_cast<unsigned long long>(extra.commands_out),
                   static_cast<unsigned long long>(extra.commands_in),
                   static_cast<unsigned long long>(extra.stale_commands),
                   static_cast<unsigned long long>(extra.bad_samples));
    if (options_.latency && state_ages_.count() > 0)
      std::fprintf(stderr,
                   "afhub bridge dds: mirrored state age (source publish to publish here, "
                   "%llu states): p50 %lld us, p99 %lld us, max %lld us\n",
                   static_cast<unsigned long long>(state_ages_.count()),
                   static_cast<long long>(state_ages_.quantile_us(0.5)),
                   static_cast<long long>(state_ages_.quantile_us(0.99)),
                   static_cast<long long>(state_ages_.max_us()));
    if (options_.latency && command_ages_.count() > 0)
      std::fprintf(stderr,
                   "afhub bridge dds: applied command age (the commander's publish to applied "
                   "here, by the DDS source timestamp, %llu commands): p50 %lld us, p99 %lld us, "
                   "max %lld us\n",
                   static_cast<unsigned long long>(command_ages_.count()),
                   static_cast<long long>(command_ages_.quantile_us(0.5)),
                   static_cast<long long>(command_ages_.quantile_us(0.99)),
                   static_cast<long long>(command_ages_.max_us()));
  }

  bool is_mirrored(std::string_view channel) const {
    for (const MirroredBody& body : mirrored_)
      if (body.channel == channel) return true;
    return false;
  }

  // New local bodies matching the globs (not those this bridge mirrors itself). A body
  // whose state reader finds no iceoryx subscriber port left is not exported, said once;
  // the next scan tries again (after the first refusal, a scan tries no more).
  void scan_catalog(CatalogReader& catalog) {
    const BodyList& list = catalog.latest();
    std::string refusal;
    for (std::uint32_t i = 0; i < list.body_count; ++i) {
      const std::string channel(name_of(list.bodies[i].channel));
      if (!matches_any(channel, options_.body_globs) || is_mirrored(channel) ||
          devices_and_world_->mirrors(channel))
        continue;
      bool known = false;
      for (const ExportedBody& body : exported_) known = known || body.channel == channel;
      if (known) continue;
      const BodyEntry entry = entry_of(list, i);
      if (entry.info.kind != ChannelKind::kBody) continue;
      ExportedBody body{channel, nullptr, nullptr};
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
      state_arrival_.attach(body.state->raw());  // when full: by the cycle alone
      if (ros2_) ros2_->add_body(channel, entry.joint_names, *body.state);
      exported_.push_back(std::move(body));
      // Its joint names, once, for mirrors (transient local: late ones too).
      afhub_dds_BodyInfo info{};
      std::snprintf(info.body, sizeof info.body, "%s", channel.c_str());
      std::vector<std::array<char, 64>> names(entry.joint_names.size());
      for (std::size_t j = 0; j < entry.joint_names.size(); ++j)
        set_name(names[j], entry.joint_names[j]);
      info.joint_names._buffer = reinterpret_cast<char(*)[64]>(names.data());
      info.joint_names._length = info.joint_names._maximum =
          static_cast<std::uint32_t>(names.size());
      info.joint_names._release = false;
      check(dds_write(info_writer_->id, &info), "writing a body's info");
      std::fprintf(stderr, "afhub bridge dds: exporting %s (%zu joints)\n", channel.c_str(),
                   entry.joint_names.size());
    }
  }

  void export_states() {
    const std::int64_t now_ns = options_.body_rate_hz > 0.0 ? monotonic_ns() : 0;
    for (std::size_t i = 0; i < exported_.size(); ++i) {
      ExportedBody& body = exported_[i];
      const BodyState* state = body.state->latest();
      if (!state || !body.state->updated()) continue;
      if (options_.body_rate_hz > 0.0) {  // newest wins: the states in between stay here
        if (static_cast<double>(now_ns - body.last_out_ns) < 1e9 / options_.body_rate_hz) continue;
        body.last_out_ns = now_ns;
      }
      to_dds(body.channel, *state, state_out_);
      if (dds_write(state_writer_->id, &state_out_) >= 0) ++counters_.states_out;
      if (ros2_) ros2_->publish(i, *state);
    }
  }

  // Commands from the network, only with --accept-commands; a command older than the
  // bound by its DDS source timestamp is dropped, never applied late.
  void import_commands() {
    void* samples[1] = {&command_in_};
    dds_sample_info_t info;
    const auto max_age_ns = static_cast<std::int64_t>(options_.max_command_age_s * 1e9);
    while (dds_take(command_reader_->id, samples, &info, 1, 1) > 0) {
      if (!info.valid_data) continue;
      const std::int64_t age_ns = dds_time() - info.source_timestamp;
      if (age_ns > max_age_ns) {
        ++counters_.stale_commands;
        continue;
      }
      if (options_.latency) command_ages_.record(age_ns);
      ExportedBody* body = find_exported(command_in_.body);
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
  bool open_command_writer(ExportedBody& body) {
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

  ExportedBody* find_exported(const char* channel) {
    for (ExportedBody& body : exported_)
      if (body.channel == channel) return &body;
    return nullptr;
  }

  MirroredBody* find_mirrored(const char* channel) {
    for (MirroredBody& body : mirrored_)
      if (body.channel == channel) return &body;
    return nullptr;
  }

  // Remote bodies announced on DDS become this hub's bodies, owned by this process.
  void mirror_infos() {
    void* samples[1] = {nullptr};  // loaned from the reader: joint name lists vary
    dds_sample_info_t info;
    while (dds_take(info_reader_->id, samples, &info, 1, 1) > 0) {
      const auto* body_info = static_cast<const afhub_dds_BodyInfo*>(samples[0]);
      if (info.valid_data && matches_any(body_info->body, options_.body_globs) &&
          !find_mirrored(body_info->body))
        add_mirrored(*body_info);
      dds_return_loan(info_reader_->id, samples, 1);
      samples[0] = nullptr;
    }
  }

  void add_mirrored(const afhub_dds_BodyInfo& info) {
    const std::string channel(info.body);
    std::vector<std::string> joint_names;
    for (std::uint32_t j = 0; j < info.joint_names._length; ++j)
      joint_names.emplace_back(info.joint_names._buffer[j]);
    try {
      check_room_for_bodies({channel}, 1);
      MirroredBody body{channel, static_cast<std::uint32_t>(joint_names.size()),
                        std::make_unique<BodyPublisher>(channel)};
      directory_->add(make_body_entry(channel, joint_names));
      directory_->publish();
      state_arrival_.attach(body.publisher->command_reader());  // when full: by the cycle
      mirrored_.push_back(std::move(body));
      std::fprintf(stderr, "afhub bridge dds: mirroring %s (%zu joints)\n", channel.c_str(),
                   joint_names.size());
    } catch (const Error& error) {
      std::fprintf(stderr, "afhub bridge dds: not mirroring %s: %s\n", channel.c_str(),
                   error.what());
      refused_.push_back(channel);
    }
  }

  void mirror_states() {
    void* samples[1] = {&state_in_};
    dds_sample_info_t info;
    while (dds_take(state_reader_->id, samples, &info, 1, 1) > 0) {
      if (!info.valid_data) continue;
      MirroredBody* body = find_mirrored(state_in_.body);
      if (!body) continue;  // its info has not come yet
      BodyState* state = body->publisher->loan_state(body->joints);
      if (!state) continue;
      from_dds(state_in_, *state);
      body->publisher->publish_state(state);
      if (options_.latency) state_ages_.record(monotonic_ns() - state_in_.header.source_stamp_ns);
      ++counters_.states_in;
    }
  }

  // Commands written here to mirrored bodies go to their owner, stamped with their
  // age: the DDS source timestamp is when the local controller published.
  void export_mirrored_commands() {
    for (MirroredBody& body : mirrored_) {
      const BodyCommand* command = body.publisher->latest_command();
      if (!command || !body.publisher->command_updated()) continue;
      to_dds(body.channel, *command, command_out_);
      const std::int64_t age_ns =
          std::max<std::int64_t>(0, monotonic_ns() - command->header.publish_stamp_ns);
      if (dds_write_ts(command_writer_->id, &command_out_, dds_time() - age_ns) >= 0)
        ++counters_.commands_out;
    }
  }

  const DdsBridgeOptions& options_;
  std::unique_ptr<Entity> domain_;  // --interface: the domain made with that binding
  std::unique_ptr<Entity> participant_, state_topic_, command_topic_, info_topic_;
  std::unique_ptr<Entity> state_writer_, info_writer_, command_reader_;
  std::unique_ptr<Entity> state_reader_, info_reader_, command_writer_;
  std::unique_ptr<Ros2Profile> ros2_;  // --profile ros2; deleted before the participant
  // Out: written on the loop's thread; in: taken on Cyclone's (on_data).
  afhub_dds_BodyState state_out_{}, state_in_{};
  afhub_dds_BodyCommand command_out_{}, command_in_{};
  // Local states and commands to mirrored bodies. Before exported_ and mirrored_:
  // destroyed after their readers.
  SampleWaiter state_arrival_;
  std::mutex mutex_;  // the bodies' lists, between the loop and Cyclone's thread (on_data)
  std::vector<ExportedBody> exported_;
  std::vector<MirroredBody> mirrored_;
  std::vector<std::string> refused_;
  std::set<std::string> not_exported_;  // no subscriber port for their state reader, said once
  std::unique_ptr<DirectoryPublisher> directory_;         // the mirrored bodies, for the catalog
  std::unique_ptr<DeviceWorldBridge> devices_and_world_;  // --devices, --world
  Counters counters_;
  AgeHistogram state_ages_;    // --latency: source publish to mirror publish
  AgeHistogram command_ages_;  // --latency: commander's publish to applied here
};

}  // namespace

bool matches_any(const std::string& channel, const std::vector<std::string>& globs) {
  for (const std::string& glob : globs)
    if (fnmatch(glob.c_str(), channel.c_str(), 0) == 0) return true;
  return false;
}

void check_dds_bridge_options(const DdsBridgeOptions& options) {
  if (!options.export_bodies && !options.mirror)
    throw Error(
        "say what to bridge: --export (this hub's bodies out), --mirror (remote "
        "bodies in), or both");
  if (options.accept_commands && !options.export_bodies)
    throw Error("--accept-commands applies commands to exported bodies: add --export");
  if (!(options.rate_hz > 0.0 && options.rate_hz <= 100'000.0))
    throw Error("--rate must be between 0 and 100000 Hz");
  if (!(options.max_command_age_s > 0.0 && options.max_command_age_s <= 10.0))
    throw Error("--max-command-age must be between 0 and 10 s");
  check_cpu_wake_latency_option(options.cpu_wake_latency_us);
  if (options.domain > 232) throw Error("--domain must be 0 to 232 (DDS domain ids)");
  if (options.body_globs.empty()) throw Error("--bodies needs at least one glob");
  if (!options.profile.empty() && options.profile != "ros2")
    throw Error("--profile " + options.profile +
                ": unknown; the one profile is ros2 (afhub's own types are always published)");
  if (options.profile == "ros2" && !options.export_bodies)
    throw Error("--profile ros2 publishes exported bodies as ROS 2 topics: add --export");
  if (!options.security_dir.empty()) {
    Qos checked;  // the files, before anything starts
    add_security_properties(checked.qos, options.security_dir);
  }
  for (const double rate : {options.body_rate_hz, options.device_rate_hz, options.world_rate_hz})
    if (!(rate >= 0.0 && rate <= 100'000.0))
      throw Error("--body-rate, --device-rate and --world-rate must be 0 (no limit) to 100000 Hz");
  if (options.world && options.export_bodies && options.mirror)
    throw Error(
        "--world with both --export and --mirror: a hub has one world, either its own or a "
        "remote one; run one bridge per direction");
  check_interface_name(options.interface);
}

int run_dds_bridge(const DdsBridgeOptions& options) {
  check_dds_bridge_options(options);
  install_stop_signal_handlers();
  signal(SIGUSR1, request_report);
  if (options.cpu_wake_latency_us >= 0)
    hold_cpu_wake_latency(options.cpu_wake_latency_us, "afhub bridge dds");
  connect_to_hub("bridge-dds", HubPolicy::kRequire);
  Bridge bridge(options);
  return bridge.run();
}

}  // namespace afhub::bridges
