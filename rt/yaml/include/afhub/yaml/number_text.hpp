// Numbers as users write them (flags, CSV fields, a viewer's form) and as messages
// write them back.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace afhub::yaml {

// `value` as messages write numbers ("1e+09", "0.001"): in six significant digits, or as
// many more as it takes to read back the same number (two times a trajectory said were
// out of order differed past the sixth, and read the same).
std::string number_text(double value);

// A decimal number as a user writes one ("0.3", "-1e-3", " +2 "): nothing when the text
// is anything else (hexadecimal, "inf", "nan") or beyond a double's range, which strtod
// read as 16, an infinity or 0.
std::optional<double> parse_finite(std::string_view text);

}  // namespace afhub::yaml
