// Finding live channels through iceoryx's service discovery: the instances that
// publish {"afhub", *, event} now, and one reader kept per live instance.
#pragma once

#include <map>
#include <memory>
#include <set>
#include <string>
#include <string_view>

namespace iox::runtime {
class ServiceDiscovery;
}

namespace afhub {

class ChannelDiscovery {
 public:
  ChannelDiscovery();
  ~ChannelDiscovery();

  // The instances of every live {"afhub", instance, event} publisher.
  std::set<std::string> live_instances(std::string_view event);

  // Keeps `readers` to one per live instance of `event`: drops the vanished ones,
  // opens the new ones with make(instance), which may give nullptr (not opened now:
  // tried again on the next call). True when the set changed.
  template <class Reader, class Make>
  bool follow(std::string_view event, std::map<std::string, std::unique_ptr<Reader>>& readers,
              Make make) {
    const std::set<std::string> live = live_instances(event);
    const auto dropped =
        std::erase_if(readers, [&](const auto& entry) { return !live.count(entry.first); });
    bool changed = dropped > 0;
    for (const std::string& instance : live) {
      if (readers.count(instance)) continue;
      auto reader = make(instance);
      if (!reader) continue;
      readers[instance] = std::move(reader);
      changed = true;
    }
    return changed;
  }

 private:
  std::unique_ptr<iox::runtime::ServiceDiscovery> discovery_;
};

}  // namespace afhub
