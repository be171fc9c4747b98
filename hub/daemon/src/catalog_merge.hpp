// The catalog's merge, apart from any channel: every live process's directory in,
// the catalog's body list out. Directories come from other processes and are
// untrusted: one that names a body that cannot be a channel is refused whole, with
// a message, and never stops the others from being listed.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "afhub/hub/bodies.hpp"
#include "afhub/shm_layout/catalog.hpp"

namespace afhub {

// A directory as read from its channel (check_payload passed): the runtime that
// publishes it, and its list.
struct OfferedDirectory {
  std::string_view instance;
  const BodyList* list = nullptr;
};

// What is wrong with a directory's entry, naming the field; empty when it can be listed.
std::string body_info_problem(const BodyInfo& body);

// The catalog after `listed` (the current catalog) meets `directories`: a body two
// processes offer goes to the one the catalog already lists, else to the first;
// bodies listed keep their place, new ones join while there is room (kMaxBodies).
// What was refused, and why, is appended to `messages`, one line each.
std::vector<BodyEntry> merge_directories(const std::vector<BodyEntry>& listed,
                                         const std::vector<OfferedDirectory>& directories,
                                         std::vector<std::string>& messages);

}  // namespace afhub
