// A reader's iceoryx subscriber, shared by channel.cpp (which reads it) and
// sample_waiter.cpp (which waits on it). Internal to the hub client.
#pragma once

#include "afhub/hub/channel.hpp"
#include "iceoryx_posh/popo/untyped_subscriber.hpp"

namespace afhub {

struct RawLatestReader::Port {
  explicit Port(const ChannelId& channel);
  iox::popo::UntypedSubscriber subscriber;
};

}  // namespace afhub
