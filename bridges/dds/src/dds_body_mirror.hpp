// `afhub bridge dds --mirror`, for bodies: bodies announced on DDS ("afhub/body_info")
// become this hub's bodies, owned by the bridge and listed in its directory (within
// its bounds: mirror_directory.hpp); their "afhub/body_state" samples are published
// into the hub as they arrive, and the commands written to them here go back out as
// "afhub/body_command" samples, stamped with their age. Bodies are claimed off the
// loop (mirror_claims.hpp), so that a slow claim stalls neither states nor commands.
// In steady state nothing here allocates: samples are made once with full-capacity
// sequences, and bodies are looked up in a vector made when they appear.
#pragma once

#include <dds/dds.h>

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "afhub/bridges/dds_bridge.hpp"
#include "afhub/hub/bodies.hpp"
#include "afhub/hub/sample_waiter.hpp"
#include "afhub/rt/latency_histogram.hpp"
#include "afhub_dds.h"
#include "dds_body_topics.hpp"
#include "dds_entity.hpp"
#include "mirror_claims.hpp"
#include "mirror_directory.hpp"

namespace afhub::bridges {

struct MirrorCounters {
  std::uint64_t states_in = 0, commands_out = 0;
};

class BodyMirror {
 public:
  // `arrivals` is woken by each command written here to a mirrored body, `directory`
  // lists the mirrored bodies, and `claims` claims them; all must outlive this, and
  // `claims` must stop before this goes (its claims use it).
  BodyMirror(dds_entity_t participant, const BodyTopics& topics, const DdsBridgeOptions& options,
             SampleWaiter& arrivals, MirrorDirectory& directory, MirrorClaims& claims);
  ~BodyMirror();  // Cyclone's thread is done with this before anything goes
  BodyMirror(const BodyMirror&) = delete;
  BodyMirror& operator=(const BodyMirror&) = delete;

  // On the loop's thread: bodies newly announced (asked of the claims), and commands to
  // mirrored bodies out.
  void take_announcements();
  void export_commands() noexcept;
  // Whether this bridge mirrors `channel` (never exported back).
  bool mirrors(std::string_view channel) const noexcept;

  std::size_t size() const noexcept { return mirrored_.size(); }
  MirrorCounters counters() const;
  // With --latency, the mirrored states' ages.
  void report() const;

 private:
  struct Body {
    std::string channel;
    std::uint32_t joints = 0;
    std::unique_ptr<BodyPublisher> publisher;
  };

  static void on_states(dds_entity_t reader, void* self);
  void mirror_states();
  void ask(const afhub_dds_BodyInfo& info);
  MirrorClaims::Install claim(const std::string& channel, std::uint32_t announced_joints,
                              const std::vector<std::string>& joint_names);  // claims' thread
  void install(Body body);
  Body* find(std::string_view channel) noexcept;

  const DdsBridgeOptions& options_;
  SampleWaiter& arrivals_;
  MirrorDirectory& directory_;  // the claims' thread's
  MirrorClaims& claims_;
  Entity state_reader_, info_reader_, command_writer_;
  afhub_dds_BodyState state_in_{};       // taken on Cyclone's thread (on_states)
  afhub_dds_BodyCommand command_out_{};  // written on the loop's thread
  // The bodies grow on the loop's thread under the mutex, which Cyclone's thread holds
  // while it publishes states; the loop reads them without it.
  mutable std::mutex mutex_;
  std::vector<Body> mirrored_;
  MirrorCounters counters_;
  LatencyHistogram state_ages_;  // --latency: source publish to publish here
};

}  // namespace afhub::bridges
