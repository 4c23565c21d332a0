#include <mpm/core/finite_guard.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

namespace mpm {

namespace {
//! Whether some of the n values is NaN or infinite (an OR that does not depend on the order).
bool any_non_finite(const double* values, std::size_t n) {
  std::uint64_t any = 0;
  for (std::size_t i = 0; i < n; ++i) any |= non_finite_bit(values[i]);
  return any != 0;
}
}  // namespace

bool all_finite(const double* values, std::size_t n) {
  constexpr std::size_t block = std::size_t{1} << 15;
  if (n <= block) return !any_non_finite(values, n);
  return !tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, block), false,
      [&](const tbb::blocked_range<std::size_t>& r, bool found) {
        return found || any_non_finite(values + r.begin(), r.size());
      },
      [](bool a, bool b) { return a || b; });
}

}  // namespace mpm
