// AMBF's lookup of a referenced body (see body_scope.hpp), with one departure: where
// AMBF takes the first of several bodies a reference could mean, this refuses the
// reference and lists them, since which one was meant is a guess.
#include "body_scope.hpp"

#include "file_reader.hpp"

namespace afhub::physics::adf {
namespace {

std::string in_file_key(int file_index, const std::string& name) {
  return std::to_string(file_index) + "\n" + name;
}

// Doubled slashes removed, so that "/ambf/env//BODY a" and "/ambf/env/BODY a" agree.
std::string without_doubled_slashes(std::string text) {
  std::string out;
  for (char c : text)
    if (c != '/' || out.empty() || out.back() != '/') out += c;
  return out;
}

}  // namespace

std::string qualified_identifier(const std::string& name_space, const std::string& identifier) {
  return without_doubled_slashes(name_space + "/" + identifier);
}

BodyScope::BodyScope(const Model& model, const std::vector<std::string>& copy_suffix)
    : model_(model), copy_suffix_(copy_suffix) {
  for (int b = 0; b < static_cast<int>(model.bodies.size()); ++b) {
    const BodySpec& body = model.bodies[b];
    in_file_.emplace(in_file_key(body.file_index, body.identifier), b);
    in_file_.emplace(in_file_key(body.file_index, body.qualified_identifier), b);
    by_identifier_[body.identifier].push_back(b);
    by_qualified_[body.qualified_identifier].push_back(b);
    if (!copy_suffix[b].empty())
      by_qualified_[body.qualified_identifier + copy_suffix[b]].push_back(b);
  }
}

int BodyScope::find(const std::string& reference, const Referrer& from, const SourceLocation& where,
                    const std::string& role, const std::string& owner) const {
  const bool qualified = reference.starts_with('/');
  const std::string written = qualified ? without_doubled_slashes(reference) : reference;
  // 1. The referring block's own file.
  if (auto own = in_file_.find(in_file_key(from.file_index, written)); own != in_file_.end())
    return own->second;
  // 2. The qualified name: as written, or in the referring block's namespace.
  const std::vector<int>* candidates = nullptr;
  const std::string full = qualified ? written : qualified_identifier(from.name_space, written);
  if (auto found = by_qualified_.find(full); found != by_qualified_.end())
    candidates = &found->second;
  // 3. Every loaded file.
  if (!candidates && !qualified)
    if (auto found = by_identifier_.find(written); found != by_identifier_.end())
      candidates = &found->second;
  if (!candidates)
    fail(where, role + " '" + reference + "' of " + owner +
                    " is not a loaded body; list it in a 'bodies' header of a loaded file");
  if (candidates->size() == 1) return candidates->front();
  std::string list;
  for (int b : *candidates) {
    const BodySpec& body = model_.bodies[b];
    list += "\n  '" + body.qualified_identifier + copy_suffix_[b] + "' (channel '" + body.channel +
            "', " + body.where.str() + ")";
  }
  fail(where, role + " '" + reference + "' of " + owner + " is ambiguous: " +
                  std::to_string(candidates->size()) + " loaded bodies match it in other files;" +
                  " write the one you mean by its qualified name:" + list);
}

}  // namespace afhub::physics::adf
