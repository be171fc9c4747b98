// A reader's iceoryx subscriber, shared by channel.cpp (which reads it) and
// sample_waiter.cpp (which waits on it), and the iceoryx service of a channel, which
// step_tape.cpp's ports use too. Internal to the hub client.
#pragma once

#include "afhub/hub/channel.hpp"
#include "iceoryx_posh/popo/untyped_subscriber.hpp"

namespace afhub {

// The iceoryx service of a channel whose names were validated.
iox::capro::ServiceDescription describe_channel(const ChannelId& channel);

// A subscriber that keeps the newest sample only, and takes the last one published
// before it came (a latest-value reader's, a step tape's ring).
iox::popo::SubscriberOptions newest_sample_only() noexcept;

struct RawLatestReader::Port {
  explicit Port(const ChannelId& channel);
  iox::popo::UntypedSubscriber subscriber;
};

}  // namespace afhub
