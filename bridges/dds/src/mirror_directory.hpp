// The bodies and devices a mirroring `afhub bridge dds` publishes into this hub, in
// its directory for the catalog. Bounded, so that a peer announcing more than fits
// neither aborts the bridge nor fills the hub: an entry is refused (with the reason)
// when the mirror already has max_entries (room stays in the catalog for the hub's
// own bodies), or when the directory with it would pass half the largest chunk the
// hub's mempools hold for a catalog (the catalog, which lists the local bodies too, is
// one chunk; iceoryx aborts a process that loans a chunk larger than its largest pool).
#pragma once

#include <cstddef>
#include <set>
#include <string>
#include <vector>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/channel.hpp"

namespace afhub::bridges {

class MirrorDirectory {
 public:
  // Needs connect_to_hub(); reads the hub's mempools from its Health.
  explicit MirrorDirectory(std::size_t max_entries);
  // Throws afhub::Error saying why when `entry` would not fit.
  void check_room(const BodyEntry& entry) const;
  // Adds `entry` (checked first) and publishes the directory; throws afhub::Error,
  // the directory as it was, when it does not fit or shared memory is exhausted.
  void add(const BodyEntry& entry);

 private:
  std::size_t bytes_with(const BodyEntry& entry) const;

  RawWriter writer_;  // this process's directory, as DirectoryPublisher's
  std::size_t max_entries_, max_bytes_;
  std::vector<BodyEntry> entries_;
  std::size_t joint_refs_ = 0;
  std::set<std::string> joint_names_;  // each distinct name once, as the directory holds them
};

}  // namespace afhub::bridges
