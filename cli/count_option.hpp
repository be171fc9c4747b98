// Whole-number options. CLI11 reads an unsigned value with strtoull, which takes
// "-1" for 2^64-1 (a run that never ends) and saturates past the type's range;
// a count option takes decimal digits only, within its type.
#pragma once

#include <CLI/CLI.hpp>
#include <charconv>
#include <limits>
#include <string>
#include <type_traits>

namespace afhub::cli {

template <class Count>
CLI::Option* add_count_option(CLI::App* app, const std::string& name, Count& value,
                              const std::string& description) {
  static_assert(std::is_unsigned_v<Count>);
  const CLI::Validator whole_number(
      [](std::string& text) -> std::string {
        Count parsed{};
        const char* end = text.data() + text.size();
        auto [stop, error] = std::from_chars(text.data(), end, parsed);
        if (text.empty() || error != std::errc() || stop != end)
          return "takes a whole number from 0 to " +
                 std::to_string(std::numeric_limits<Count>::max()) + ", got '" + text + "'";
        return {};
      },
      "COUNT");
  return app->add_option(name, value, description)->check(whole_number);
}

}  // namespace afhub::cli
