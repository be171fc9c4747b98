// A recursive-descent JSON parser for tests (see json_tree.hpp).
#include "json_tree.hpp"

#include <cctype>
#include <cstdlib>
#include <stdexcept>

namespace afhub::test {
namespace {

class Parser {
 public:
  explicit Parser(const std::string& text) : text_(text) {}

  JsonValue document() {
    JsonValue value = parse_value();
    skip_space();
    if (at_ != text_.size()) fail("text after the document");
    return value;
  }

 private:
  [[noreturn]] void fail(const std::string& what) {
    throw std::runtime_error("JSON at offset " + std::to_string(at_) + ": " + what);
  }
  void skip_space() {
    while (at_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[at_]))) ++at_;
  }
  bool take(char c) {
    skip_space();
    if (at_ < text_.size() && text_[at_] == c) {
      ++at_;
      return true;
    }
    return false;
  }
  void expect(char c) {
    if (!take(c)) fail(std::string("expected '") + c + "'");
  }
  bool take_word(const char* word) {
    const std::string w = word;
    if (text_.compare(at_, w.size(), w) != 0) return false;
    at_ += w.size();
    return true;
  }

  std::string parse_string() {
    expect('"');
    std::string out;
    while (at_ < text_.size() && text_[at_] != '"') {
      char c = text_[at_++];
      if (c == '\\' && at_ < text_.size()) {
        const char escaped = text_[at_++];
        c = escaped == 'n' ? '\n' : escaped == 't' ? '\t' : escaped;
        if (escaped == 'u') {
          c = static_cast<char>(std::strtol(text_.substr(at_, 4).c_str(), nullptr, 16));
          at_ += 4;
        }
      }
      out += c;
    }
    expect('"');
    return out;
  }

  JsonValue parse_value() {
    skip_space();
    JsonValue value;
    if (at_ >= text_.size()) fail("unexpected end");
    const char c = text_[at_];
    if (c == '{') {
      value.type = JsonValue::Type::kObject;
      expect('{');
      if (take('}')) return value;
      do {
        skip_space();
        std::string key = parse_string();
        expect(':');
        if (value.members.count(key)) fail("duplicate key '" + key + "'");
        value.members[key] = parse_value();
      } while (take(','));
      expect('}');
    } else if (c == '[') {
      value.type = JsonValue::Type::kArray;
      expect('[');
      if (take(']')) return value;
      do value.items.push_back(parse_value());
      while (take(','));
      expect(']');
    } else if (c == '"') {
      value.type = JsonValue::Type::kString;
      value.text = parse_string();
    } else if (take_word("true") || take_word("false")) {
      value.type = JsonValue::Type::kBool;
      value.boolean = c == 't';
    } else if (take_word("null")) {
      value.type = JsonValue::Type::kNull;
    } else {
      char* end = nullptr;
      value.type = JsonValue::Type::kNumber;
      value.number = std::strtod(text_.c_str() + at_, &end);
      if (end == text_.c_str() + at_) fail("expected a value");
      at_ = static_cast<std::size_t>(end - text_.c_str());
    }
    return value;
  }

  const std::string& text_;
  std::size_t at_ = 0;
};

}  // namespace

const JsonValue& JsonValue::at(const std::string& key) const {
  const auto found = members.find(key);
  if (found == members.end()) throw std::runtime_error("JSON: no member '" + key + "'");
  return found->second;
}

JsonValue parse_json(const std::string& text) {
  return Parser(text).document();
}

}  // namespace afhub::test
