// A latest-value reader for a process that must not trust the channel's writers (the
// hub, the viewer): each new payload is copied out of shared memory and checked there,
// and only the copy is used. A check made in place proves nothing: every member of the
// hub's group can write the chunk between the check and a later read of the same count.
// Costs one copy per new sample; for channels read now and then, not for 1 kHz loops.
// A slot's reader copies and checks already (see channel.hpp): on a slot kind this one
// hands that copy on.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "afhub/hub/channel.hpp"

namespace afhub {

class CopyingReader {
 public:
  CopyingReader(const ChannelId& channel, PayloadKind kind);

  // The copy of the newest valid payload, or nullptr before the first one. It stays
  // unchanged until the next call. A payload whose copy fails the check is refused
  // (said once, counted), and the previous copy is kept.
  const void* latest();
  // Whether the last latest() call took a new copy.
  bool updated() const { return updated_; }
  std::uint64_t refused_count() const { return reader_.refused_count() + refused_; }
  const ChannelId& channel() const { return reader_.channel(); }

 private:
  RawLatestReader reader_;
  PayloadKind kind_;
  std::vector<std::max_align_t> copy_;   // aligned for every payload struct
  std::vector<std::max_align_t> spare_;  // the next copy, until it is checked
  bool have_copy_ = false;
  bool updated_ = false;
  std::uint64_t refused_ = 0;
};

// A CopyingReader of one payload type.
template <class T>
class CopiedReader {
 public:
  explicit CopiedReader(const ChannelId& channel) : reader_(channel, T::kKind) {}
  const T* latest() { return static_cast<const T*>(reader_.latest()); }
  bool updated() const { return reader_.updated(); }

 private:
  CopyingReader reader_;
};

}  // namespace afhub
