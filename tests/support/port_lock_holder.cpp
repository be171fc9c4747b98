// A client that dies the way a client killed inside publish() does: holding its
// publisher's lock (on synth/body0's command channel, which synth reads) and its
// subscriber queue's lock (on synth/body0's state, which synth writes every
// millisecond). Exits 2 if it cannot get there within 5 s; otherwise it never
// returns, it SIGKILLs itself: at once, or after the seconds given as its argument
// (long enough for the hub to have listed it).
#include <signal.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <thread>

#include "afhub/hub/hub_presence.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "iceoryx_posh/internal/popo/ports/publisher_port_user.hpp"
#include "iceoryx_posh/internal/popo/ports/subscriber_port_user.hpp"
#include "iceoryx_posh/runtime/posh_runtime.hpp"
#include "port_lock_repair.hpp"

namespace {

iox::capro::ServiceDescription describe(const afhub::ChannelId& channel) {
  using iox::capro::IdString_t;
  using iox::cxx::TruncateToCapacity;
  return {IdString_t(TruncateToCapacity, channel.service.c_str()),
          IdString_t(TruncateToCapacity, channel.instance.c_str()),
          IdString_t(TruncateToCapacity, channel.event.c_str())};
}

}  // namespace

int main(int argc, char** argv) {
  afhub::connect_to_hub("lock-holder", afhub::HubPolicy::kRequire);
  auto& runtime = iox::runtime::PoshRuntime::getInstance();
  auto* publisher_data =
      runtime.getMiddlewarePublisher(describe(afhub::body_command_channel("synth/body0")));
  auto* subscriber_data =
      runtime.getMiddlewareSubscriber(describe(afhub::body_state_channel("synth/body0")));
  iox::popo::PublisherPortUser publisher(publisher_data);
  iox::popo::SubscriberPortUser subscriber(subscriber_data);
  publisher.offer();
  subscriber.subscribe();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (!publisher.hasSubscribers() ||
         subscriber.getSubscriptionState() != iox::SubscribeState::SUBSCRIBED) {
    if (std::chrono::steady_clock::now() > deadline) {
      std::fprintf(stderr, "port_lock_holder: not connected to synth/body0 within 5 s\n");
      return 2;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (argc > 1) std::this_thread::sleep_for(std::chrono::duration<double>(std::atof(argv[1])));
  pthread_mutex_lock(&afhub::native_mutex(publisher_data->m_chunkSenderData));
  pthread_mutex_lock(&afhub::native_mutex(subscriber_data->m_chunkReceiverData));
  raise(SIGKILL);
}
