// afhub-dds-bench: the processes of bench/dds_bridge.sh (`afhub bridge dds` measured
// between two network namespaces). Every path carries the bridge's own DDS types at
// the bridge's QoS (best effort, keep last 1; --reliable: reliable): a BodyState of
// 32 joints (about 1 KiB serialized) out, a BodyCommand of 32 joints back.
//   raw-ping N FILE / raw-pong   Cyclone DDS alone: the reference round trip.
//   hub-ping N FILE / hub-pong   afhub -> bridge -> DDS -> bridge -> afhub and back: the
//                                ping owns body bench/ping on its hub; the pong, on the
//                                other hub, answers each mirrored state with a command.
//   writes BODIES N              N states of 7 joints written over BODIES keys as the
//                                bridge writes them, between two SIGUSR2s: under the
//                                malloc-count library, Cyclone's own allocations per write.
//   sink SECONDS                 reads the bridge's states from DDS and prints, once a
//                                second, how many came and how old they were (source
//                                publish to here; one host, one monotonic clock).
// A ping writes one round-trip time in nanoseconds per line to FILE (appending) and
// prints how many pings went unanswered within 100 ms (best effort may drop them).
#include <dds/dds.h>

#include <signal.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/body_claims.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/sample_waiter.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/rt/percentile.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub_dds.h"
#include "dds_convert.hpp"

namespace afhub::bench {
namespace {

constexpr std::uint32_t kJoints = 32;
constexpr std::int64_t kAnswerTimeoutNs = 100'000'000;
constexpr std::int64_t kPingPeriodNs = 1'000'000;  // one ping a millisecond, like states
constexpr const char* kPingBody = "bench/ping";

bool reliable() {
  const char* value = std::getenv("AFHUB_DDS_BENCH_RELIABLE");
  return value && std::string(value) == "1";
}

dds_entity_t check(dds_entity_t result, const char* what) {
  if (result < 0) throw Error(std::string("DDS: ") + what + ": " + dds_strretcode(result));
  return result;
}

// The bridge's stream QoS (see dds_bridge.cpp).
dds_qos_t* stream_qos() {
  dds_qos_t* qos = dds_create_qos();
  if (reliable())
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  else
    dds_qset_reliability(qos, DDS_RELIABILITY_BEST_EFFORT, 0);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
  return qos;
}

// A reader or a writer of the bridge's body state topic, with its stream QoS.
dds_entity_t body_state_endpoint(dds_entity_t participant, bool writes) {
  const dds_entity_t topic = check(dds_create_topic(participant, &afhub_dds_BodyState_desc,
                                                    "afhub/body_state", nullptr, nullptr),
                                   "state topic");
  dds_qos_t* qos = stream_qos();
  const dds_entity_t endpoint =
      writes ? check(dds_create_writer(participant, topic, qos, nullptr), "writer")
             : check(dds_create_reader(participant, topic, qos, nullptr), "reader");
  dds_delete_qos(qos);
  return endpoint;
}

// One participant with a state and a command topic, a writer on one and a reader on
// the other, and a waitset woken by the reader's data.
struct RawEndpoint {
  dds_entity_t participant = 0, writer = 0, reader = 0, waitset = 0;

  RawEndpoint(const char* state_topic, const char* command_topic, bool writes_states) {
    participant =
        check(dds_create_participant(DDS_DOMAIN_DEFAULT, nullptr, nullptr), "participant");
    const dds_entity_t states = check(
        dds_create_topic(participant, &afhub_dds_BodyState_desc, state_topic, nullptr, nullptr),
        "state topic");
    const dds_entity_t commands = check(
        dds_create_topic(participant, &afhub_dds_BodyCommand_desc, command_topic, nullptr, nullptr),
        "command topic");
    dds_qos_t* qos = stream_qos();
    writer = check(dds_create_writer(participant, writes_states ? states : commands, qos, nullptr),
                   "writer");
    reader = check(dds_create_reader(participant, writes_states ? commands : states, qos, nullptr),
                   "reader");
    dds_delete_qos(qos);
    waitset = check(dds_create_waitset(participant), "waitset");
    const dds_entity_t arrived =
        check(dds_create_readcondition(reader, DDS_ANY_STATE), "condition");
    check(dds_waitset_attach(waitset, arrived, 0), "attach");
  }
  ~RawEndpoint() { dds_delete(participant); }

  // Until the peer's reader and writer are matched (discovery over the veth).
  void wait_matched() const {
    for (int i = 0; i < 3000 && !stop_requested(); ++i) {
      dds_publication_matched_status_t out{};
      dds_subscription_matched_status_t in{};
      dds_get_publication_matched_status(writer, &out);
      dds_get_subscription_matched_status(reader, &in);
      if (out.current_count > 0 && in.current_count > 0) return;
      sleep_until_ns(monotonic_ns() + 10'000'000);
    }
    throw Error("DDS: the peer was not discovered within 30 s (check CYCLONEDDS_URI)");
  }
};

void fill_state(afhub_dds_BodyState& sample, std::uint64_t ping) {
  sample.header.sequence_number = ping;
  sample.header.source_stamp_ns = monotonic_ns();
  sample.joints._length = kJoints;
  for (std::uint32_t j = 0; j < kJoints; ++j)
    sample.joints._buffer[j] = {static_cast<double>(ping), 0.0, 0.0};
}

// Writes the round trips and prints the count of the unanswered.
struct RoundTrips {
  std::vector<std::int64_t> ns;
  std::uint64_t lost = 0;

  void write(const char* path, const char* label) const {
    FILE* file = std::fopen(path, "a");
    if (!file) throw Error(std::string("cannot write ") + path);
    for (std::int64_t value : ns) std::fprintf(file, "%lld\n", static_cast<long long>(value));
    std::fclose(file);
    std::printf("%s: %zu round trips, %llu unanswered within 100 ms\n", label, ns.size(),
                static_cast<unsigned long long>(lost));
  }
};

int raw_ping(std::uint64_t pings, const char* path) {
  RawEndpoint endpoint("bench/raw_state", "bench/raw_command", true);
  endpoint.wait_matched();
  afhub_dds_BodyState state{};
  afhub_dds_BodyCommand command{};
  bridges::make_state_sample(state);
  bridges::make_command_sample(command);
  std::snprintf(state.body, sizeof state.body, "%s", kPingBody);
  RoundTrips trips;
  trips.ns.reserve(pings);
  std::int64_t next_ns = monotonic_ns();
  for (std::uint64_t ping = 1; ping <= pings && !stop_requested(); ++ping) {
    sleep_until_ns(next_ns);
    next_ns += kPingPeriodNs;
    fill_state(state, ping);
    const std::int64_t sent_ns = state.header.source_stamp_ns;
    check(dds_write(endpoint.writer, &state), "write");
    bool answered = false;
    for (std::int64_t now = monotonic_ns(); !answered && now - sent_ns < kAnswerTimeoutNs;
         now = monotonic_ns()) {
      dds_waitset_wait(endpoint.waitset, nullptr, 0, kAnswerTimeoutNs - (now - sent_ns));
      void* samples[1] = {&command};
      dds_sample_info_t info;
      while (dds_take(endpoint.reader, samples, &info, 1, 1) > 0)
        if (info.valid_data && command.header.sequence_number == ping) answered = true;
    }
    if (answered)
      trips.ns.push_back(monotonic_ns() - sent_ns);
    else
      ++trips.lost;
  }
  trips.write(path, "raw DDS");
  bridges::free_state_sample(state);
  bridges::free_command_sample(command);
  return 0;
}

int raw_pong() {
  RawEndpoint endpoint("bench/raw_state", "bench/raw_command", false);
  afhub_dds_BodyState state{};
  afhub_dds_BodyCommand command{};
  bridges::make_state_sample(state);
  bridges::make_command_sample(command);
  std::snprintf(command.body, sizeof command.body, "%s", kPingBody);
  command.joints._length = kJoints;
  while (!stop_requested()) {
    dds_waitset_wait(endpoint.waitset, nullptr, 0, DDS_MSECS(100));
    void* samples[1] = {&state};
    dds_sample_info_t info;
    while (dds_take(endpoint.reader, samples, &info, 1, 1) > 0) {
      if (!info.valid_data) continue;
      command.header.sequence_number = state.header.sequence_number;
      for (std::uint32_t j = 0; j < kJoints; ++j)
        command.joints._buffer[j] = {state.joints._buffer[0].position, 1};  // kPosition
      check(dds_write(endpoint.writer, &command), "write");
    }
  }
  bridges::free_state_sample(state);
  bridges::free_command_sample(command);
  return 0;
}

std::vector<std::string> joint_names() {
  std::vector<std::string> names;
  for (std::uint32_t j = 0; j < kJoints; ++j) names.push_back("ping-joint" + std::to_string(j));
  return names;
}

int hub_ping(std::uint64_t pings, const char* path) {
  connect_to_hub("bench-hub-ping", HubPolicy::kRequire);
  check_room_for_bodies({kPingBody}, 2);
  DirectoryPublisher directory;
  directory.add(make_body_entry(kPingBody, joint_names()));
  BodyPublisher body(kPingBody);
  directory.publish();
  confirm_body_claims({kPingBody}, kClaimConfirmTimeout);
  SampleWaiter command_arrival;
  command_arrival.attach(body.command_reader());
  // Until the pong answers: the bridges discover each other and the mirror appears.
  RoundTrips trips;
  trips.ns.reserve(pings);
  const std::int64_t give_up_ns = monotonic_ns() + 60'000'000'000;
  std::int64_t next_ns = monotonic_ns();
  std::uint64_t ping = 0;
  bool warm = false;
  while (trips.ns.size() + trips.lost < pings && !stop_requested()) {
    sleep_until_ns(next_ns);
    next_ns += kPingPeriodNs;
    ++ping;
    BodyState* state = body.loan_state(kJoints);
    if (!state) throw Error("shared memory exhausted");
    for (std::uint32_t j = 0; j < kJoints; ++j)
      state->joints[j].position = static_cast<double>(ping);
    const std::int64_t sent_ns = monotonic_ns();
    body.publish_state(state);
    bool answered = false;
    for (std::int64_t now = sent_ns; !answered && now - sent_ns < kAnswerTimeoutNs;
         now = monotonic_ns()) {
      command_arrival.wait(kAnswerTimeoutNs - (now - sent_ns));
      const BodyCommand* command = body.latest_command();
      if (command && body.command_updated() && command->joint_count > 0 &&
          command->joints[0].value == static_cast<double>(ping))
        answered = true;
    }
    if (!warm) {  // pings before the first answer only wait for the path to exist
      warm = answered;
      if (!warm && monotonic_ns() > give_up_ns)
        throw Error("no answer through the bridges within 60 s");
      continue;
    }
    if (answered)
      trips.ns.push_back(monotonic_ns() - sent_ns);
    else
      ++trips.lost;
  }
  trips.write(path, "afhub through the bridges");
  return 0;
}

int hub_pong() {
  connect_to_hub("bench-hub-pong", HubPolicy::kRequire);
  const BodyEntry entry = wait_for_body(kPingBody, "afhub-dds-bench hub-pong", INT64_MAX);
  BodyClient body(entry);
  SampleWaiter state_arrival;
  state_arrival.attach(body.state_reader());
  while (!stop_requested()) {
    state_arrival.wait(100'000'000);
    const BodyState* state = body.latest_state();
    if (!state || !body.state_updated() || state->joint_count == 0) continue;
    BodyCommand* command = body.loan_command(kJoints);
    if (!command) continue;
    for (std::uint32_t j = 0; j < kJoints; ++j)
      command->joints[j] = {state->joints[0].position, JointCommandType::kPosition};
    body.publish_command(command);
  }
  return 0;
}

// Percentile of sorted values, in microseconds.
double quantile_us(const std::vector<std::int64_t>& sorted, double q) {
  return static_cast<double>(percentile_of_sorted<std::int64_t>(sorted, q)) * 1e-3;
}

int sink(double seconds) {
  dds_entity_t participant =
      check(dds_create_participant(DDS_DOMAIN_DEFAULT, nullptr, nullptr), "participant");
  const dds_entity_t reader = body_state_endpoint(participant, false);
  const char* slow = std::getenv("AFHUB_DDS_BENCH_SLOW_MS");
  const std::int64_t pause_ns = slow ? std::atoll(slow) * 1'000'000 : 1'000'000;
  afhub_dds_BodyState state{};
  bridges::make_state_sample(state);
  std::vector<std::int64_t> ages;
  ages.reserve(1'000'000);
  const std::int64_t start_ns = monotonic_ns();
  std::int64_t report_ns = start_ns + 1'000'000'000;
  while (!stop_requested() && static_cast<double>(monotonic_ns() - start_ns) * 1e-9 < seconds) {
    void* samples[1] = {&state};
    dds_sample_info_t info;
    while (dds_take(reader, samples, &info, 1, 1) > 0)
      if (info.valid_data) ages.push_back(monotonic_ns() - state.header.source_stamp_ns);
    if (monotonic_ns() >= report_ns) {
      std::sort(ages.begin(), ages.end());
      std::printf("{\"t_s\": %.1f, \"states\": %zu, \"age_p50_us\": %.0f, \"age_max_us\": %.0f}\n",
                  static_cast<double>(report_ns - start_ns) * 1e-9, ages.size(),
                  quantile_us(ages, 0.5), quantile_us(ages, 1.0));
      std::fflush(stdout);
      ages.clear();
      report_ns += 1'000'000'000;
    }
    sleep_until_ns(monotonic_ns() + pause_ns);  // a slow reader: takes only what is newest
  }
  bridges::free_state_sample(state);
  dds_delete(participant);
  return 0;
}

int writes(std::uint32_t bodies, std::uint64_t count) {
  dds_entity_t participant =
      check(dds_create_participant(DDS_DOMAIN_DEFAULT, nullptr, nullptr), "participant");
  const dds_entity_t writer = body_state_endpoint(participant, true);
  afhub_dds_BodyState state{};
  bridges::make_state_sample(state);
  state.joints._length = 7;
  // Every key once first: a new instance allocates, as a new body does in the bridge.
  for (std::uint32_t body = 0; body < bodies; ++body) {
    std::snprintf(state.body, sizeof state.body, "writes/body%u", body);
    check(dds_write(writer, &state), "write");
  }
  // The count is printed by the malloc-count library's SIGUSR2 handler: without it,
  // SIGUSR2 would end this process.
  const bool counted = std::getenv("LD_PRELOAD") != nullptr;
  if (counted) raise(SIGUSR2);
  for (std::uint64_t i = 0; i < count; ++i) {
    std::snprintf(state.body, sizeof state.body, "writes/body%u",
                  static_cast<unsigned>(i % bodies));
    state.header.source_stamp_ns = monotonic_ns();
    check(dds_write(writer, &state), "write");
  }
  if (counted) raise(SIGUSR2);
  std::printf("writes: %llu\n", static_cast<unsigned long long>(count));
  bridges::free_state_sample(state);
  dds_delete(participant);
  return 0;
}

int usage() {
  std::fprintf(stderr,
               "usage: afhub-dds-bench raw-ping N FILE | raw-pong | hub-ping N FILE | hub-pong | "
               "writes BODIES N | sink SECONDS\n");
  return 2;
}

}  // namespace
}  // namespace afhub::bench

int main(int argc, char** argv) {
  using namespace afhub::bench;
  try {
    afhub::install_stop_signal_handlers();
    const std::string mode = argc > 1 ? argv[1] : "";
    if (mode == "raw-ping" && argc == 4)
      return raw_ping(std::strtoull(argv[2], nullptr, 10), argv[3]);
    if (mode == "raw-pong" && argc == 2) return raw_pong();
    if (mode == "hub-ping" && argc == 4)
      return hub_ping(std::strtoull(argv[2], nullptr, 10), argv[3]);
    if (mode == "hub-pong" && argc == 2) return hub_pong();
    if (mode == "writes" && argc == 4)
      return writes(static_cast<std::uint32_t>(std::strtoul(argv[2], nullptr, 10)),
                    std::strtoull(argv[3], nullptr, 10));
    if (mode == "sink" && argc == 3) return sink(std::atof(argv[2]));
    return usage();
  } catch (const afhub::Error& error) {
    std::fprintf(stderr, "afhub-dds-bench: %s\n", error.what());
    return 1;
  }
}
