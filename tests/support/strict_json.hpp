// JSON in tests, read strictly (RFC 8259) with nlohmann::json: NaN, Infinity, hex
// numbers, comments, bad escapes, invalid UTF-8, duplicate keys and text after the
// document are errors, so a test catches invalid JSON that afhub writes.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace afhub::test {

// The document in `text`; throws std::runtime_error naming the error and quoting the
// text when it is not valid JSON (a test then fails with that message).
nlohmann::json parse_json(const std::string& text);

// The element of the array `items` whose member `key` equals `value`, or nullptr when
// there is none; throws std::runtime_error when there are several (never a first match).
const nlohmann::json* find_element(const nlohmann::json& items, const std::string& key,
                                   const nlohmann::json& value);

}  // namespace afhub::test
