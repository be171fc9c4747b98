// `afhub bridge dds` (see dds_bridge.hpp): one loop at --rate that exports local bodies
// (dds_body_export.hpp) and mirrors remote ones (dds_body_mirror.hpp), devices and the
// world beside them (dds_device_world.hpp). States and commands from DDS never wait
// for this loop: Cyclone's thread that receives them publishes them into the hub. Nor
// does this loop wait for the hub to make room for a newly mirrored body or device: a
// thread of their own claims them (mirror_claims.hpp). The catalog is rescanned for new
// bodies once a second (which may allocate; it is not per message).
#include "afhub/bridges/dds_bridge.hpp"

#include <dds/dds.h>
#include <sched.h>
#include <signal.h>

#include <cstdio>
#include <memory>
#include <string_view>

#include "afhub/bridges/dds_bridge_config.hpp"
#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/sample_waiter.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/rt/cpu_wake_latency.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "dds_body_export.hpp"
#include "dds_body_mirror.hpp"
#include "dds_body_topics.hpp"
#include "dds_device_world.hpp"
#include "dds_entity.hpp"
#include "dds_security.hpp"
#include "mirror_claims.hpp"
#include "mirror_directory.hpp"

namespace afhub::bridges {
namespace {

// SIGUSR1: print the counters now (tests read them at a moment they choose).
volatile sig_atomic_t report_requested = 0;
void request_report(int) {
  report_requested = 1;
}

class Bridge {
 public:
  explicit Bridge(const DdsBridgeOptions& options) : options_(options) {
    if (!options.interface.empty())
      domain_ =
          Entity(dds_create_domain(options.domain, interface_config(options.interface).c_str()),
                 "binding the domain to the --interface");
    const Qos participant;
    if (!options.security_dir.empty())
      add_security_properties(participant.get(), options.security_dir);
    participant_ = Entity(
        dds_create_participant(options.domain, participant.get(), nullptr),
        options.security_dir.empty()
            ? "creating the participant"
            : "creating a secure participant (are the --security files valid: the "
              "certificate signed by identity_ca.pem, the .p7s signed by permissions_ca.pem?)");
    const dds_entity_t p = participant_.id();
    topics_ = std::make_unique<BodyTopics>(p);
    if (options.mirror) {
      directory_ = std::make_unique<MirrorDirectory>(options.max_mirrored);
      claims_ = std::make_unique<MirrorClaims>(MirrorClaims::Limits{});
      mirror_ =
          std::make_unique<BodyMirror>(p, *topics_, options, arrivals_, *directory_, *claims_);
    }
    if (options.export_bodies)
      export_ = std::make_unique<BodyExport>(p, *topics_, options, arrivals_);
    devices_and_world_ =
        std::make_unique<DeviceWorldBridge>(p, options, directory_.get(), claims_.get());
  }

  int run() {
    std::unique_ptr<CatalogReader> catalog;
    if (export_) {
      catalog = std::make_unique<CatalogReader>();
      catalog->wait(std::chrono::milliseconds(2000));
    }
    const auto mirrored = [this](std::string_view channel) {
      return (mirror_ && mirror_->mirrors(channel)) || devices_and_world_->mirrors(channel);
    };
    const auto period_ns = static_cast<std::int64_t>(1e9 / options_.rate_hz);
    const std::int64_t start_ns = monotonic_ns();
    say_if_insecure();
    std::int64_t next_ns = start_ns, next_scan_ns = start_ns,
                 next_report_ns = start_ns + 5'000'000'000;
    while (!stop_requested()) {
      const std::int64_t now_ns = monotonic_ns();
      if (!hub_lost()) {
        if (catalog && now_ns >= next_scan_ns) {
          export_->scan(catalog->latest(), mirrored);
          devices_and_world_->scan(catalog->latest());
          next_scan_ns = now_ns + 1'000'000'000;
        }
        if (mirror_) mirror_->take_announcements();
        if (claims_) claims_->install_claimed();
      }
      if (now_ns >= next_report_ns || report_requested) {
        report_requested = 0;
        report();
        next_report_ns = now_ns + 5'000'000'000;
      }
      forward_local();
      if (options_.seconds > 0.0 &&
          static_cast<double>(now_ns - start_ns) * 1e-9 >= options_.seconds)
        break;
      next_ns += period_ns;
      if (next_ns < now_ns) next_ns = now_ns;  // after a stall: no burst of catch-up cycles
      wait_until(next_ns);
    }
    report();
    return 0;
  }

 private:
  // Until `deadline_ns`, forwarding local states and commands to mirrored bodies as they
  // come: they wake the iceoryx WaitSet (or, with spin, are polled for).
  void wait_until(std::int64_t deadline_ns) {
    for (std::int64_t now_ns = monotonic_ns(); now_ns < deadline_ns && !stop_requested();
         now_ns = monotonic_ns()) {
      if (options_.spin || hub_lost())
        sched_yield();
      else
        arrivals_.wait(deadline_ns - now_ns);
      forward_local();
    }
  }

  // This hub's side: exported states, commands written to mirrored bodies, and the
  // inputs polled rather than heard (ROS 2 commands, devices, the world). Nothing once
  // the hub is lost: the process re-attaches to the next (hub_loss.hpp).
  void forward_local() {
    if (hub_lost()) return;
    if (export_) {
      export_->export_states();
      devices_and_world_->export_states(monotonic_ns());
      if (options_.accept_commands) {
        export_->import_ros2_commands();
        devices_and_world_->import_commands();
      }
    }
    if (mirror_) {
      mirror_->export_commands();
      devices_and_world_->mirror();
    }
  }

  // At start and in each status: commands taken from anyone on the domain.
  void say_if_insecure() const {
    if (options_.accept_commands && options_.security_dir.empty())
      std::fprintf(stderr,
                   "afhub bridge dds: INSECURE: applying commands from any host on DDS domain %u "
                   "(--insecure-accept-commands; --security DIR authenticates them)\n",
                   static_cast<unsigned>(options_.domain));
  }

  void report() {
    say_if_insecure();
    const ExportCounters out = export_ ? export_->counters() : ExportCounters{};
    const MirrorCounters in = mirror_ ? mirror_->counters() : MirrorCounters{};
    std::fprintf(stderr,
                 "afhub bridge dds: exported %zu bodies, mirrored %zu; states out %llu in %llu, "
                 "commands out %llu in %llu, stale commands dropped %llu, bad %llu\n",
                 export_ ? export_->size() : 0, mirror_ ? mirror_->size() : 0,
                 static_cast<unsigned long long>(out.states_out),
                 static_cast<unsigned long long>(in.states_in),
                 static_cast<unsigned long long>(in.commands_out),
                 static_cast<unsigned long long>(out.commands_in),
                 static_cast<unsigned long long>(out.stale_commands),
                 static_cast<unsigned long long>(out.bad_commands));
    if (export_) export_->report();
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
    if (claims_) claims_->report();
    if (mirror_) mirror_->report();
  }

  // Destroyed in reverse: the bodies and devices (their listeners stopped first) before
  // their topics, the participant and its domain; the waiter after the readers it watches.
  const DdsBridgeOptions& options_;
  Entity domain_;  // --interface: the domain made with that binding
  Entity participant_;
  std::unique_ptr<BodyTopics> topics_;
  SampleWaiter arrivals_;                       // local states and commands to mirrored bodies
  std::unique_ptr<MirrorDirectory> directory_;  // the mirrored bodies and devices
  std::unique_ptr<BodyMirror> mirror_;
  std::unique_ptr<BodyExport> export_;
  std::unique_ptr<DeviceWorldBridge> devices_and_world_;  // --devices, --world
  // Last, so first to go: its thread stops before the mirror and devices its claims use.
  std::unique_ptr<MirrorClaims> claims_;
};

}  // namespace

int run_dds_bridge(const DdsBridgeOptions& options) {
  check_dds_bridge_options(options);
  install_stop_signal_handlers();
  signal(SIGUSR1, request_report);
  if (options.cpu_wake_latency_us >= 0)
    hold_cpu_wake_latency(options.cpu_wake_latency_us, "afhub bridge dds");
  survive_hub_loss("afhub bridge dds");
  connect_to_hub("bridge-dds", HubPolicy::kRequire);
  Bridge bridge(options);
  return bridge.run();
}

}  // namespace afhub::bridges
