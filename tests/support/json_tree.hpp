// A small JSON reader for tests: parses a document into a tree so that a test can
// check its shape (which keys, which types) as well as its values.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace afhub::test {

struct JsonValue {
  enum class Type { kNull, kBool, kNumber, kString, kArray, kObject } type = Type::kNull;
  bool boolean = false;
  double number = 0.0;
  std::string text;
  std::vector<JsonValue> items;
  std::map<std::string, JsonValue> members;

  bool has(const std::string& key) const { return members.count(key) != 0; }
  // The member `key`; throws std::runtime_error naming the key when it is missing.
  const JsonValue& at(const std::string& key) const;
};

// Throws std::runtime_error with the offset of the first error.
JsonValue parse_json(const std::string& text);

}  // namespace afhub::test
