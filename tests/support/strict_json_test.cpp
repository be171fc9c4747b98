// The tests' JSON reader is strict: what RFC 8259 forbids fails the test, with the
// text in the message, and escapes decode to the characters they stand for.
#include "strict_json.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <stdexcept>
#include <string>

namespace afhub::test {
namespace {

TEST(StrictJson, RejectsWhatJsonForbidsAndQuotesTheText) {
  for (const std::string text : {R"({"a": nan})",
                                 R"({"a": NaN})",
                                 R"({"a": inf})",
                                 R"({"a": -Infinity})",
                                 R"({"a": 0x10})",
                                 R"({"a": 010})",
                                 R"({"a": +1})",
                                 R"({"a": .5})",
                                 R"({"a": 1} x)",
                                 R"({"a": 1}{"b": 2})",
                                 R"({"a": "\x"})",
                                 R"({"a": "\u12"})",
                                 R"({"a": "\ud800"})",
                                 "{\"a\": \"\t\"}",
                                 "{\"a\": \"\xff\"}",
                                 R"({'a': 1})",
                                 R"({"a": 1,})",
                                 R"([1, 2,])",
                                 R"({"a": 1 /* c */})",
                                 R"({"a": 1, "a": 2})",
                                 R"({"b": {"a": 1, "a": 1}})",
                                 "",
                                 " "}) {
    try {
      parse_json(text);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const std::runtime_error& error) {
      EXPECT_NE(std::string(error.what()).find("in: " + text), std::string::npos) << error.what();
    }
  }
}

TEST(StrictJson, DecodesEscapes) {
  const nlohmann::json json =
      parse_json(R"({"r": "\r", "b": "\b", "f": "\f", "e": "\u00e9", "n": "\n", "t": "\t",)"
                 R"( "q": "\"\\\/", "smile": "\ud83d\ude00", "zero": "a\u0000b"})");
  EXPECT_EQ(json.at("r"), "\r");
  EXPECT_EQ(json.at("b"), "\b");
  EXPECT_EQ(json.at("f"), "\f");
  EXPECT_EQ(json.at("e"), "\xc3\xa9");  // é in UTF-8
  EXPECT_EQ(json.at("n"), "\n");
  EXPECT_EQ(json.at("t"), "\t");
  EXPECT_EQ(json.at("q"), "\"\\/");
  EXPECT_EQ(json.at("smile"), "\xf0\x9f\x98\x80");  // U+1F600 from its surrogate pair
  EXPECT_EQ(json.at("zero"), std::string("a\0b", 3));
}

TEST(StrictJson, ReadsNumbersExactly) {
  const nlohmann::json json = parse_json(R"([0.1, -2.5e-3, 1E3, 18446744073709551615, -0])");
  EXPECT_EQ(json.at(0).get<double>(), 0.1);  // the shortest round-trip text reads back
  EXPECT_EQ(json.at(1).get<double>(), -2.5e-3);
  EXPECT_EQ(json.at(2).get<double>(), 1000.0);
  EXPECT_EQ(json.at(3).get<std::uint64_t>(), 18446744073709551615u);
  EXPECT_EQ(json.at(4).get<double>(), 0.0);
}

TEST(StrictJson, FindsTheOneElementWithAKeyNeverTheFirstOfSeveral) {
  const nlohmann::json loops =
      parse_json(R"([{"name": "run", "pid": 7}, {"name": "ctl hold", "pid": 8}, {"pid": 9}])");
  const nlohmann::json* hold = find_element(loops, "name", "ctl hold");
  ASSERT_NE(hold, nullptr);
  EXPECT_EQ(hold->at("pid"), 8);
  EXPECT_EQ(find_element(loops, "pid", 7)->at("name"), "run");
  EXPECT_EQ(find_element(loops, "name", "ctl sine"), nullptr);
  EXPECT_THROW(find_element(parse_json(R"([{"a": 1}, {"a": 1}])"), "a", 1), std::runtime_error);
  EXPECT_THROW(find_element(parse_json(R"({"a": 1})"), "a", 1), std::runtime_error);
}

}  // namespace
}  // namespace afhub::test
