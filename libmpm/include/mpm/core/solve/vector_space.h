#pragma once
//! The vector operations the Krylov solvers need, for std::vector of scalars (one unknown per
//! cell) and of fixed-size Eigen vectors (all components of a node velocity solved at once
//! with the same operator). They run in parallel over blocks of kVectorBlock entries; a
//! reduction sums each block in index order and then the blocks' sums in block order, so a
//! solve gives the same bits on every run and thread count (and a vector of one block the
//! bits of the plain loop).
#include <Eigen/Core>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <type_traits>
#include <vector>

namespace mpm::solve {

//! The additive identity of an element type.
template <class T>
T zero() {
  if constexpr (std::is_arithmetic_v<T>)
    return T(0);
  else
    return T::Zero();
}

//! The Euclidean inner product of two element values.
template <class T>
double inner(const T& a, const T& b) {
  if constexpr (std::is_arithmetic_v<T>)
    return a * b;
  else
    return a.dot(b);
}

//! Entries per block of the parallel vector operations: large enough that a block's work
//! outweighs its task (and that a small system, one block, stays serial with the plain loop's
//! bits).
inline constexpr std::size_t kVectorBlock = std::size_t{1} << 14;

//! f(i) for every i in [0, n), in parallel over blocks (the calls must write distinct entries).
template <class F>
void for_each_entry(std::size_t n, F&& f) {
  const auto block = [&](std::size_t first, std::size_t last) {
    for (std::size_t i = first; i < last; ++i) f(i);
  };
  if (n <= kVectorBlock) return block(0, n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kVectorBlock),
                    [&](const tbb::blocked_range<std::size_t>& r) { block(r.begin(), r.end()); });
}

//! The sum of partial(first, last) over the blocks of kVectorBlock indices of [0, n), computed
//! in parallel and added in block order: the same bits on every run and thread count.
template <class F>
double sum_by_blocks(std::size_t n, F&& partial) {
  if (n <= kVectorBlock) return partial(std::size_t{0}, n);
  std::vector<double> sums((n + kVectorBlock - 1) / kVectorBlock);
  tbb::parallel_for(std::size_t{0}, sums.size(),
                    [&](std::size_t k) { sums[k] = partial(k * kVectorBlock, std::min(n, (k + 1) * kVectorBlock)); });
  double s = 0.0;
  for (const double p : sums) s += p;
  return s;
}

//! The Euclidean inner product of two vectors of equal size (summed by blocks, see above).
template <class T>
double dot(const std::vector<T>& a, const std::vector<T>& b) {
  return sum_by_blocks(a.size(), [&](std::size_t first, std::size_t last) {
    double s = 0.0;
    for (std::size_t i = first; i < last; ++i) s += inner(a[i], b[i]);
    return s;
  });
}

}  // namespace mpm::solve
