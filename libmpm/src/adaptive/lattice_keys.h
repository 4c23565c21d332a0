// Sorting keys that pack a lattice point (a block, a cell) in a fixed number of bits per axis.
#pragma once

#include <mpm/core/types.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <vector>

namespace mpm::adaptive {

//! Sorts `keys` and drops the repeats, where a key packs a point of a lattice in `bits` bits per
//! axis, axis 0 in the lowest bits (SparseGrid's block keys, CellTree's cell keys): so the key
//! order is the lexicographic order of the points, the last axis slowest. The lists the
//! adaptive set-up builds repeat most keys (a bucket adds its 2^dim patch blocks, a particle
//! the cells its box meets): a bitmap over the points' bounding box, read in order, when the box
//! is not much larger than the list; otherwise a comparison sort.
template <int dim>
void sort_unique_points(std::vector<std::uint64_t>& keys, int bits) {
  if (keys.empty()) return;
  const std::uint64_t mask = (std::uint64_t{1} << bits) - 1;
  const auto point = [&](std::uint64_t key) {
    IVec<dim> c;
    for (int a = 0; a < dim; ++a, key >>= bits) c[a] = static_cast<int>(key & mask);
    return c;
  };
  IVec<dim> lo = point(keys.front()), hi = lo;
  for (const std::uint64_t key : keys) {
    const IVec<dim> c = point(key);
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  const IVec<dim> extent = hi - lo + IVec<dim>::Ones();
  const double box = extent.template cast<double>().prod();
  if (box > 64.0 * static_cast<double>(keys.size()) + 4096.0) {
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    return;
  }
  std::vector<std::uint64_t> marked((static_cast<std::size_t>(box) + 63) / 64, 0);
  for (const std::uint64_t key : keys) {
    const IVec<dim> c = point(key) - lo;
    std::size_t flat = 0;
    for (int a = dim - 1; a >= 0; --a) flat = flat * static_cast<std::size_t>(extent[a]) + c[a];
    marked[flat / 64] |= std::uint64_t{1} << (flat % 64);
  }
  keys.clear();
  for (std::size_t i = 0; i < marked.size(); ++i)
    for (std::uint64_t word = marked[i]; word != 0; word &= word - 1) {
      std::size_t flat = 64 * i + static_cast<std::size_t>(std::countr_zero(word));
      std::uint64_t key = 0;
      for (int a = 0; a < dim; ++a) {
        key |= static_cast<std::uint64_t>(lo[a] + static_cast<int>(flat % static_cast<std::size_t>(extent[a])))
               << (a * bits);
        flat /= static_cast<std::size_t>(extent[a]);
      }
      keys.push_back(key);
    }
}

}  // namespace mpm::adaptive
