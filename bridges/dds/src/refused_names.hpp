// The names a mirroring bridge was refused (a body or device that did not fit, or
// whose name a local process holds), and when: a name refused less than retry_after
// ago is not claimed again, so that a peer repeating it costs no claim each time, and
// one refused for a reason that passes (a local holder gone) is mirrored later.
// Bounded: when full, the name refused longest ago is forgotten (it may be tried, and
// said, again sooner). Lookups allocate nothing.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace afhub::bridges {

class RefusedNames {
 public:
  RefusedNames(std::size_t capacity, std::int64_t retry_after_ns);

  // Records that `name` was refused at `now_ns`; true when it was not listed (a
  // refusal to say).
  bool add(std::string_view name, std::int64_t now_ns);
  // Whether `name` was refused less than retry_after before `now_ns`.
  bool recent(std::string_view name, std::int64_t now_ns) const noexcept;
  std::size_t size() const noexcept { return entries_.size(); }

 private:
  struct Entry {
    std::string name;
    std::int64_t refused_ns = 0;
  };
  Entry* find(std::string_view name) noexcept;

  std::size_t capacity_;
  std::int64_t retry_after_ns_;
  std::vector<Entry> entries_;
};

}  // namespace afhub::bridges
