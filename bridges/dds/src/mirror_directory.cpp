// A mirror's bounded directory (see mirror_directory.hpp).
#include "mirror_directory.hpp"

#include <algorithm>
#include <chrono>
#include <thread>

#include "afhub/hub/hub_presence.hpp"
#include "afhub/shm_layout/catalog.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/health.hpp"

namespace afhub::bridges {
namespace {

// The largest payload a chunk of the hub's payload mempools holds, from its Health
// (the first, in a hub's first second, may list no pools yet); 0 when none says.
// Segment 0 is RouDi's own introspection, whose chunks no afhub writer gets.
std::size_t largest_chunk_bytes() {
  LatestReader<Health> health(
      ChannelId{std::string(kService), std::string(kHubInstance), std::string(kHealthEvent)});
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(2500);
  for (;;) {
    std::size_t largest = 0;
    if (const Health* latest = health.latest())
      for (std::uint32_t i = 0; i < std::min<std::uint32_t>(latest->mempool_count, kMaxMempools);
           ++i)
        if (latest->mempools[i].segment_id > 0)
          largest = std::max<std::size_t>(largest, latest->mempools[i].chunk_payload_bytes);
    if (largest > 0 || std::chrono::steady_clock::now() > deadline) return largest;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

}  // namespace

MirrorDirectory::MirrorDirectory(std::size_t max_entries)
    : writer_({std::string(kService), runtime_name(), std::string(kDirectoryEvent)},
              PayloadKind::kBodyDirectory),
      max_entries_(max_entries),
      // A list past the largest tier is never loaned (loan_body_list), whatever the pools.
      max_bytes_(std::min(largest_chunk_bytes(), kBodyListTiers.back()) / 2) {
  if (max_bytes_ == 0)
    throw Error(
        "the hub's health lists no mempools: cannot tell how large a directory of mirrored "
        "bodies may be. Is the RouDi that answers an afhub hub?");
}

std::size_t MirrorDirectory::bytes_with(const BodyEntry& entry) const {
  std::size_t names = joint_names_.size();
  std::set<std::string_view> added;
  for (const std::string& name : entry.joint_names)
    if (!joint_names_.count(name) && added.insert(name).second) ++names;
  return body_list_bytes(entries_.size() + 1, names, joint_refs_ + entry.joint_names.size());
}

void MirrorDirectory::check_room(const BodyEntry& entry) const {
  if (entries_.size() >= max_entries_)
    throw Error("this bridge mirrors " + std::to_string(entries_.size()) +
                " bodies and devices already, its most (--max-mirrored), so that the hub keeps "
                "room for its own; mirror fewer (--bodies) or raise --max-mirrored");
  if (const std::size_t bytes = bytes_with(entry); bytes > max_bytes_)
    throw Error("with its " + std::to_string(entry.joint_names.size()) +
                " joint names, the directory of mirrored bodies would take " +
                std::to_string(bytes) +
                " bytes, more than half the hub's largest chunk for a catalog (" +
                std::to_string(max_bytes_ * 2) + " bytes); mirror fewer bodies (--bodies)");
}

void MirrorDirectory::add(const BodyEntry& entry) {
  check_room(entry);
  entries_.push_back(entry);
  BodyList* list = loan_body_list(writer_, entries_);
  if (!list) {
    entries_.pop_back();
    throw Error(
        "shared memory is exhausted: no chunk for the directory of mirrored bodies; "
        "give the hub a larger pool (`afhub hub --pool BYTES:COUNT`)");
  }
  writer_.publish(list);
  joint_refs_ += entry.joint_names.size();
  joint_names_.insert(entry.joint_names.begin(), entry.joint_names.end());
}

}  // namespace afhub::bridges
