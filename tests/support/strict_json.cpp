// Strict JSON for tests (see strict_json.hpp).
#include "strict_json.hpp"

#include <set>
#include <stdexcept>
#include <vector>

namespace afhub::test {
namespace {

// Long documents are cut: a failure names the error's line and column anyway.
std::string quoted(const std::string& text) {
  constexpr std::size_t kShown = 4000;
  if (text.size() <= kShown) return text;
  return text.substr(0, kShown) + "... (" + std::to_string(text.size()) + " characters)";
}

}  // namespace

nlohmann::json parse_json(const std::string& text) {
  // nlohmann keeps the last of repeated keys; a writer that repeats one is wrong.
  std::vector<std::set<std::string>> keys;  // of each object open at this point
  std::string repeated;
  const auto check = [&](int, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
    using Event = nlohmann::json::parse_event_t;
    if (event == Event::object_start) {
      keys.emplace_back();
    } else if (event == Event::object_end) {
      keys.pop_back();
    } else if (event == Event::key && !keys.back().insert(parsed.get<std::string>()).second &&
               repeated.empty()) {
      repeated = parsed.get<std::string>();
    }
    return true;
  };
  try {
    nlohmann::json document = nlohmann::json::parse(text, check);
    if (!repeated.empty()) throw std::runtime_error("the key \"" + repeated + "\" repeated");
    return document;
  } catch (const std::exception& error) {
    throw std::runtime_error(std::string("invalid JSON: ") + error.what() +
                             "\nin: " + quoted(text));
  }
}

const nlohmann::json* find_element(const nlohmann::json& items, const std::string& key,
                                   const nlohmann::json& value) {
  if (!items.is_array()) throw std::runtime_error("not an array: " + quoted(items.dump()));
  const nlohmann::json* found = nullptr;
  for (const nlohmann::json& item : items) {
    if (!item.is_object() || !item.contains(key) || item.at(key) != value) continue;
    if (found)
      throw std::runtime_error("several elements with \"" + key + "\": " + value.dump() + " in " +
                               quoted(items.dump()));
    found = &item;
  }
  return found;
}

}  // namespace afhub::test
