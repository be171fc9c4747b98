// The catalog's merge (see catalog_merge.hpp).
#include "catalog_merge.hpp"

#include <map>

#include "afhub/hub/bodies.hpp"
#include "afhub/shm_layout/channel_names.hpp"

namespace afhub {

std::string body_info_problem(const BodyInfo& body) {
  if (std::string problem = channel_name_problem(name_of(body.channel)); !problem.empty())
    return "BodyInfo.channel: " + problem;
  if (body.kind != ChannelKind::kBody && body.kind != ChannelKind::kDevice)
    return "BodyInfo.kind: " + std::to_string(static_cast<std::uint32_t>(body.kind)) +
           " is neither a body (0) nor a device (1)";
  if (body.joint_count > kMaxJointsPerBody)
    return "BodyInfo.joint_count: " + std::to_string(body.joint_count) +
           " joints; a body carries at most " + std::to_string(kMaxJointsPerBody);
  return {};
}

std::vector<BodyEntry> merge_directories(const std::vector<BodyEntry>& listed,
                                         const std::vector<OfferedDirectory>& directories,
                                         std::vector<std::string>& messages) {
  std::map<std::string, std::uint32_t> listed_owner;
  for (const BodyEntry& body : listed)
    listed_owner[std::string(name_of(body.info.channel))] = body.info.owner_pid;
  // What the valid directories offer, in their order.
  std::vector<BodyEntry> offered;
  std::map<std::string, std::size_t> offered_at;
  for (const OfferedDirectory& directory : directories) {
    if (!directory.list) continue;
    const BodyList& list = *directory.list;
    const std::uint32_t count = std::min<std::uint32_t>(list.body_count, kMaxBodies);
    std::string problem;
    for (std::uint32_t i = 0; i < count && problem.empty(); ++i)
      if (std::string what = body_info_problem(list.bodies[i]); !what.empty())
        problem = "body " + std::to_string(i) + ": " + what;
    if (!problem.empty()) {
      messages.push_back("the directory of " + std::string(directory.instance) +
                         " is refused, with its " + std::to_string(count) + " bodies: " + problem +
                         "; that process is faulty or foreign (the other bodies are listed)");
      continue;
    }
    for (std::uint32_t i = 0; i < count; ++i) {
      const BodyInfo& body = list.bodies[i];
      std::string channel(name_of(body.channel));
      const auto [at, added] = offered_at.emplace(channel, offered.size());
      if (added) {
        offered.push_back(entry_of(list, i));
        continue;
      }
      messages.push_back("body " + channel + " is claimed by two processes; keeping the first");
      const auto owner = listed_owner.find(channel);
      if (owner != listed_owner.end() && owner->second == body.owner_pid)
        offered[at->second] = entry_of(list, i);
    }
  }
  // First come, first served: bodies the catalog lists keep their place, new ones
  // join while there is room. Their owner sees the refused ones missing and says so.
  std::vector<BodyEntry> merged;
  std::vector<bool> taken(offered.size(), false);
  for (const BodyEntry& body : listed) {
    const auto at = offered_at.find(std::string(name_of(body.info.channel)));
    if (at == offered_at.end() || taken[at->second]) continue;
    merged.push_back(offered[at->second]);
    taken[at->second] = true;
  }
  for (std::size_t k = 0; k < offered.size(); ++k) {
    if (taken[k]) continue;
    if (merged.size() == kMaxBodies) {
      messages.push_back("the catalog is full (" + std::to_string(kMaxBodies) + " bodies); " +
                         std::string(name_of(offered[k].info.channel)) + " of " +
                         std::string(name_of(offered[k].info.owner)) + " is refused");
      continue;
    }
    merged.push_back(offered[k]);
  }
  return merged;
}

}  // namespace afhub
