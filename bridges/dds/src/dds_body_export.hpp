// `afhub bridge dds --export`, for bodies: the states of local bodies matching the
// globs go out as "afhub/body_state" samples and their joint names once as
// "afhub/body_info" (transient local: late mirrors learn them too); with
// --accept-commands, "afhub/body_command" samples younger than the age bound go into
// the bodies' command slots; --profile ros2 adds the ROS 2 topics (ros2_profile.hpp).
// In steady state nothing here allocates: samples are made once with full-capacity
// sequences, and bodies are looked up in a vector made when they appear.
#pragma once

#include <dds/dds.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <set>
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
#include "ros2_profile.hpp"

namespace afhub::bridges {

struct ExportCounters {
  std::uint64_t states_out = 0, commands_in = 0;
  std::uint64_t stale_commands = 0, bad_commands = 0, unknown_bodies = 0;
};

class BodyExport {
 public:
  // `arrivals` is woken by each new local state; it must outlive this.
  BodyExport(dds_entity_t participant, const BodyTopics& topics, const DdsBridgeOptions& options,
             SampleWaiter& arrivals);
  ~BodyExport();  // Cyclone's thread is done with this before anything goes
  BodyExport(const BodyExport&) = delete;
  BodyExport& operator=(const BodyExport&) = delete;

  // New local bodies of `catalog`, except those `mirrored` (this bridge's own mirrors).
  void scan(const BodyList& catalog, const std::function<bool(std::string_view)>& mirrored);
  // On the loop's thread: new local states out, and the ROS 2 commands (polled) in.
  void export_states() noexcept;
  void import_ros2_commands() noexcept;

  std::size_t size() const noexcept { return exported_.size(); }
  ExportCounters counters() const;
  // The ROS 2 profile's counters and, with --latency, the commands' ages.
  void report() const;

 private:
  // A local body whose state goes out. Its command writer is made at the first
  // network command: a writer takes one of iceoryx's 512 publisher ports, and an
  // exporter of hundreds of bodies that takes no commands must not take hundreds.
  struct Body {
    std::string channel;
    std::unique_ptr<LatestReader<BodyState>> state;
    std::unique_ptr<Writer<BodyCommand>> command;
    bool command_refused = false;
    std::int64_t last_out_ns = 0;  // for --body-rate
  };

  static void on_commands(dds_entity_t reader, void* self);
  void import_commands();
  bool open_command_writer(Body& body);
  Body* find(const char* channel) noexcept;
  void announce(const std::string& channel, const std::vector<std::string>& joint_names);

  const DdsBridgeOptions& options_;
  SampleWaiter& arrivals_;
  std::unique_ptr<Ros2Profile> ros2_;  // --profile ros2
  Entity state_writer_, info_writer_, command_reader_;
  afhub_dds_BodyState state_out_{};     // written on the loop's thread
  afhub_dds_BodyCommand command_in_{};  // taken on Cyclone's (on_commands)
  // The bodies grow on the loop's thread (scan) under the mutex, which Cyclone's thread
  // holds while it applies commands; the loop reads them without it.
  mutable std::mutex mutex_;
  std::vector<Body> exported_;
  std::set<std::string> not_exported_;  // no subscriber port for their state reader, said once
  ExportCounters counters_;
  LatencyHistogram command_ages_;  // --latency: the commander's publish to applied here
};

}  // namespace afhub::bridges
