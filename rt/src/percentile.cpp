// The nearest-rank rule (see percentile.hpp).
#include "afhub/rt/percentile.hpp"

#include <cmath>

namespace afhub {

std::uint64_t percentile_rank(std::uint64_t count, double q) noexcept {
  if (count == 0) return 0;
  if (!(q < 1.0)) return count;  // and NaN
  if (q <= 0.0) return 1;
  const double exact = q * static_cast<double>(count);
  // Less a trillionth: q's binary rounding must not push a whole rank up a place
  // (0.7 * 10 is 7.000000000000001 in doubles, and its rank is 7).
  const auto rank = static_cast<std::uint64_t>(std::ceil(exact - exact * 1e-12));
  return rank < 1 ? 1 : (rank > count ? count : rank);
}

}  // namespace afhub
