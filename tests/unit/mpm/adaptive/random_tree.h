#pragma once
// Test helper: random non-graded trees. Leaves are refined at random, and a few cells are
// refined straight down to the finest level, so that coarse leaves border leaves up to
// levels - 1 levels finer (the non-graded case of Gao et al. 2017, sec. 5).
#include <mpm/adaptive/cell_tree.h>

#include <random>
#include <utility>
#include <vector>

namespace mpm::test {

template <int dim>
adaptive::CellTree<dim> random_tree(unsigned seed, int levels, int base, double dx0 = 1.0) {
  adaptive::CellTree<dim> tree(Vec<dim>::Constant(-0.5), IVec<dim>::Constant(base), dx0, levels);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int round = 0; round < levels - 1; ++round) {
    std::vector<std::pair<int, IVec<dim>>> leaves;
    tree.for_each_leaf([&](int level, const IVec<dim>& cell) { leaves.emplace_back(level, cell); });
    for (const auto& [level, cell] : leaves)
      if (level < tree.finest() && u(rng) < 0.3) tree.refine(level, cell);
  }
  // Deep spikes: one child refined down to the finest level.
  for (int spike = 0; spike < 2; ++spike) {
    IVec<dim> cell;
    for (int a = 0; a < dim; ++a) cell[a] = static_cast<int>(u(rng) * base);
    for (int level = 0; level < tree.finest(); ++level) {
      if (tree.is_leaf(level, cell)) tree.refine(level, cell);
      for (int a = 0; a < dim; ++a) cell[a] = 2 * cell[a] + (u(rng) < 0.5);
    }
  }
  return tree;
}

}  // namespace mpm::test
