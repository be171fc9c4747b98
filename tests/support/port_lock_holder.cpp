// A client that dies the way a client killed inside publish() does: holding its
// publisher's lock (on the service of blocks of command slots, which synth reads) and
// its subscriber queue's lock (on the service of blocks of state slots, which synth
// writes). Exits 2 if it cannot get there within 5 s; otherwise it never
// returns, it SIGKILLs itself: at once, or after the seconds given as its argument
// (long enough for the hub to have listed it).
#include <signal.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>

#include "afhub/hub/hub_presence.hpp"
#include "afhub/shm_layout/slot_block.hpp"
#include "iceoryx_posh/internal/popo/ports/publisher_port_user.hpp"
#include "iceoryx_posh/internal/popo/ports/subscriber_port_user.hpp"
#include "iceoryx_posh/runtime/posh_runtime.hpp"
#include "port_lock_repair.hpp"

namespace {

iox::capro::ServiceDescription blocks_of(afhub::PayloadKind kind) {
  const std::string instance = std::to_string(static_cast<std::uint32_t>(kind));
  using iox::capro::IdString_t;
  using iox::cxx::TruncateToCapacity;
  return {IdString_t(afhub::kSlotBlockService), IdString_t(TruncateToCapacity, instance.c_str()),
          IdString_t(afhub::kSlotBlockEvent)};
}

}  // namespace

int main(int argc, char** argv) {
  afhub::connect_to_hub("lock-holder", afhub::HubPolicy::kRequire);
  auto& runtime = iox::runtime::PoshRuntime::getInstance();
  auto* publisher_data =
      runtime.getMiddlewarePublisher(blocks_of(afhub::PayloadKind::kBodyCommand));
  auto* subscriber_data =
      runtime.getMiddlewareSubscriber(blocks_of(afhub::PayloadKind::kBodyState));
  iox::popo::PublisherPortUser publisher(publisher_data);
  iox::popo::SubscriberPortUser subscriber(subscriber_data);
  publisher.offer();
  subscriber.subscribe();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (!publisher.hasSubscribers() ||
         subscriber.getSubscriptionState() != iox::SubscribeState::SUBSCRIBED) {
    if (std::chrono::steady_clock::now() > deadline) {
      std::fprintf(stderr, "port_lock_holder: not connected to synth's slots within 5 s\n");
      return 2;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (argc > 1) std::this_thread::sleep_for(std::chrono::duration<double>(std::atof(argv[1])));
  pthread_mutex_lock(&afhub::native_mutex(publisher_data->m_chunkSenderData));
  pthread_mutex_lock(&afhub::native_mutex(subscriber_data->m_chunkReceiverData));
  raise(SIGKILL);
}
