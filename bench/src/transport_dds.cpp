// Cyclone DDS through its C API on loopback: what a user bridging processes over DDS
// gets on one machine. `dds`: Cyclone's shared memory off. `dds-shm`: on, so that
// Cyclone carries each sample in an iceoryx chunk of the running hub (its RouDi), the
// writer filling a loaned sample and the reader taking it in place. One topic pair per
// payload size (an IDL type of exactly that size), reliable, keep last 1. The
// receiver waits in a waitset: Cyclone delivers through its own receive thread.
#include <dds/dds.h>
#include <dds/ddsc/dds_loan_api.h>

#include <array>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <vector>

#include "afhub/shm_layout/error.hpp"
#include "bench_samples.h"
#include "transport.hpp"

namespace afhub::bench {
namespace {

struct SizedType {
  std::uint32_t bytes;
  const dds_topic_descriptor_t* descriptor;
};
const std::array<SizedType, 5> kTypes = {{
    {64, &afhub_bench_Sample64_desc},
    {1024, &afhub_bench_Sample1024_desc},
    {16384, &afhub_bench_Sample16384_desc},
    {262144, &afhub_bench_Sample262144_desc},
    {1048576, &afhub_bench_Sample1048576_desc},
}};

static_assert(sizeof(afhub_bench_Sample64) == 64 && sizeof(afhub_bench_Sample1048576) == 1048576);

// Loopback only, shared memory off or on, no tracing.
std::string config(bool shared_memory) {
  return std::string(
             "<CycloneDDS><Domain id=\"any\"><General><Interfaces><NetworkInterface "
             "name=\"lo\"/></Interfaces></General><SharedMemory><Enable>") +
         (shared_memory ? "true</Enable><LogLevel>warn</LogLevel>" : "false</Enable>") +
         "</SharedMemory><Tracing><Verbosity>none</Verbosity></Tracing></Domain></CycloneDDS>";
}

dds_entity_t check(dds_entity_t entity, const char* what) {
  if (entity < 0) throw Error(std::string("dds: ") + what + ": " + dds_strretcode(entity));
  return entity;
}

class DdsTransport : public Transport {
 public:
  DdsTransport(Side side, const std::string& session, bool shared_memory)
      : shared_memory_(shared_memory), buffer_(kMaxPayloadBytes) {
    // Each bench run has a domain of its own (and each of its two configurations):
    // parallel runs on lo do not meet.
    const auto domain = static_cast<dds_domainid_t>(
        1 + 2 * (std::hash<std::string>{}(session) % 100) + (shared_memory ? 1 : 0));
    domain_ = check(dds_create_domain(domain, config(shared_memory).c_str()), "domain");
    participant_ = check(dds_create_participant(domain, nullptr, nullptr), "participant");
    dds_qos_t* qos = dds_create_qos();
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
    waitset_ = check(dds_create_waitset(participant_), "waitset");
    for (std::size_t i = 0; i < kTypes.size(); ++i) {
      const std::string base = "afhub_bench_" + session + "_" + std::to_string(kTypes[i].bytes);
      const dds_entity_t ping = check(dds_create_topic(participant_, kTypes[i].descriptor,
                                                       (base + "_ping").c_str(), nullptr, nullptr),
                                      "topic");
      const dds_entity_t pong = check(dds_create_topic(participant_, kTypes[i].descriptor,
                                                       (base + "_pong").c_str(), nullptr, nullptr),
                                      "topic");
      writers_[i] =
          check(dds_create_writer(participant_, side == Side::kPing ? ping : pong, qos, nullptr),
                "writer");
      readers_[i] =
          check(dds_create_reader(participant_, side == Side::kPing ? pong : ping, qos, nullptr),
                "reader");
      dds_set_status_mask(readers_[i], DDS_DATA_AVAILABLE_STATUS);
      check(dds_waitset_attach(waitset_, readers_[i], static_cast<dds_attach_t>(i)), "attach");
    }
    dds_delete_qos(qos);
    if (shared_memory && !dds_is_shared_memory_available(writers_[0]))
      throw Error(
          "dds-shm: Cyclone DDS did not put its writers on shared memory (this build of "
          "libddsc has no iceoryx support, or no hub runs)");
  }

  ~DdsTransport() override { dds_delete(domain_); }

  std::int64_t send(std::uint32_t bytes, std::uint64_t round,
                    std::int64_t peer_receive_ns) override {
    const std::size_t i = index_of(bytes);
    const Stamps stamps{round, monotonic_ns(), peer_receive_ns};
    char* sample = buffer_.data();
    if (shared_memory_) {  // a sample in an iceoryx chunk, written in place
      void* loaned = nullptr;
      check(dds_loan_sample(writers_[i], &loaned), "loan");
      sample = static_cast<char*>(loaned);
    }
    std::memcpy(sample, &stamps, sizeof stamps);
    touch_written(sample + sizeof stamps, bytes - sizeof stamps, round);
    check(dds_write(writers_[i], sample), "write");
    return stamps.send_ns;
  }

  std::optional<Message> receive(std::int64_t deadline_ns) override {
    for (;;) {
      for (std::size_t i = 0; i < kTypes.size(); ++i) {
        void* samples[1] = {nullptr};
        dds_sample_info_t info;
        const dds_return_t taken = dds_take(readers_[i], samples, &info, 1, 1);
        if (taken <= 0) continue;
        std::optional<Message> message;
        if (info.valid_data) {
          Stamps stamps;
          std::memcpy(&stamps, samples[0], sizeof stamps);
          touch_read(static_cast<const char*>(samples[0]) + sizeof stamps,
                     kTypes[i].bytes - sizeof stamps, stamps.round,
                     shared_memory_ ? "dds-shm" : "dds");
          message = Message{kTypes[i].bytes, stamps.round, stamps.send_ns, stamps.peer_receive_ns,
                            monotonic_ns()};
        }
        dds_return_loan(readers_[i], samples, taken);
        if (message) return message;
      }
      const std::int64_t left = deadline_ns - monotonic_ns();
      if (left <= 0) return std::nullopt;
      dds_waitset_wait(waitset_, nullptr, 0, left);
    }
  }

 private:
  static std::size_t index_of(std::uint32_t bytes) {
    for (std::size_t i = 0; i < kTypes.size(); ++i)
      if (kTypes[i].bytes == bytes) return i;
    throw Error("dds: no IDL type of " + std::to_string(bytes) + " bytes");
  }

  bool shared_memory_;
  std::vector<char> buffer_;
  dds_entity_t domain_ = 0, participant_ = 0, waitset_ = 0;
  std::array<dds_entity_t, kTypes.size()> writers_{}, readers_{};
};

}  // namespace

std::unique_ptr<Transport> open_dds_transport(Side side, const std::string& session,
                                              bool shared_memory) {
  return std::make_unique<DdsTransport>(side, session, shared_memory);
}

}  // namespace afhub::bench
