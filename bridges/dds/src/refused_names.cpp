// Names refused, and when (see refused_names.hpp).
#include "refused_names.hpp"

#include <algorithm>

namespace afhub::bridges {

RefusedNames::RefusedNames(std::size_t capacity, std::int64_t retry_after_ns)
    : capacity_(std::max<std::size_t>(capacity, 1)), retry_after_ns_(retry_after_ns) {
  entries_.reserve(capacity_);
}

RefusedNames::Entry* RefusedNames::find(std::string_view name) noexcept {
  for (Entry& entry : entries_)
    if (entry.name == name) return &entry;
  return nullptr;
}

bool RefusedNames::add(std::string_view name, std::int64_t now_ns) {
  if (Entry* listed = find(name)) {
    listed->refused_ns = now_ns;
    return false;
  }
  if (entries_.size() < capacity_) {
    entries_.push_back({std::string(name), now_ns});
  } else {
    Entry& oldest = *std::min_element(
        entries_.begin(), entries_.end(),
        [](const Entry& a, const Entry& b) { return a.refused_ns < b.refused_ns; });
    oldest = {std::string(name), now_ns};
  }
  return true;
}

bool RefusedNames::recent(std::string_view name, std::int64_t now_ns) const noexcept {
  for (const Entry& entry : entries_)
    if (entry.name == name) return now_ns - entry.refused_ns < retry_after_ns_;
  return false;
}

}  // namespace afhub::bridges
