#pragma once
//! The fluid and the sediment each have their own sparse grid over the same lattice (same
//! origin, dx and extent: the two grids share node positions), but each grid
//! allocates only the blocks its own particles touch, so one node has a different storage
//! index in each. This walks the nodes allocated in both.
#include <mpm/core/error.h>
#include <mpm/core/sparse_grid.h>
#include <tbb/parallel_for.h>

#include <cstddef>
#include <string>

namespace coupling {

//! InputError naming `stage` unless `a` and `b` have the same origin, spacing and extent.
template <int dim>
void require_same_lattice(const mpm::SparseGrid<dim>& a, const mpm::SparseGrid<dim>& b, const std::string& stage) {
  mpm::verify<mpm::InputError>(a.dx() == b.dx() && a.origin() == b.origin() && a.node_counts() == b.node_counts(),
                               stage + ": the two phase grids must share origin, dx and extent (dx " +
                                   std::to_string(a.dx()) + " vs " + std::to_string(b.dx()) + ")");
}

//! Calls fn(index in a, index in b) for every node allocated in both grids, blocks in
//! parallel (fn must only touch its own node). Preconditions: require_same_lattice(a, b).
template <int dim, class Fn>
void for_each_shared_node(const mpm::SparseGrid<dim>& a, const mpm::SparseGrid<dim>& b, Fn&& fn) {
  constexpr int n = mpm::SparseGrid<dim>::nodes_per_block;
  tbb::parallel_for(tbb::blocked_range<int>(0, a.block_count(), 16), [&](const tbb::blocked_range<int>& r) {
    for (int sa = r.begin(); sa != r.end(); ++sa) {
      const int sb = b.slot(a.active_block_id(sa));
      if (sb < 0) continue;
      const std::size_t first_a = static_cast<std::size_t>(sa) * n, first_b = static_cast<std::size_t>(sb) * n;
      for (int l = 0; l < n; ++l) fn(first_a + l, first_b + l);
    }
  });
}

}  // namespace coupling
