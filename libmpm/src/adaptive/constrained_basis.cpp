#include <mpm/adaptive/constrained_basis.h>
#include <mpm/core/error.h>

#include <algorithm>

namespace mpm::adaptive {

namespace {

bool on_lattice(int coordinate, int scale) { return coordinate % scale == 0; }

// Appends the corners of leaf (level, cell) with their multilinear weights at lattice-unit
// position `f` (a point in the leaf's closure, in finest-lattice units), times `scale`; zero
// weights are left out.
template <int dim, class Fn>
void for_each_corner(const CellTree<dim>& tree, int level, const IVec<dim>& cell, const Vec<dim>& f, double scale,
                     Fn&& fn) {
  const int s = tree.scale(level);
  Vec<dim> t;
  for (int a = 0; a < dim; ++a) t[a] = std::clamp((f[a] - cell[a] * static_cast<double>(s)) / s, 0.0, 1.0);
  for (int corner = 0; corner < (1 << dim); ++corner) {
    double w = scale;
    IVec<dim> point;
    for (int a = 0; a < dim; ++a) {
      const int bit = (corner >> a) & 1;
      w *= bit ? t[a] : 1.0 - t[a];
      point[a] = (cell[a] + bit) * s;
    }
    if (w != 0.0) fn(point, w);
  }
}

template <int dim>
void merge(std::vector<NodeWeight<dim>>& out, std::size_t first) {
  auto less = [](const NodeWeight<dim>& a, const NodeWeight<dim>& b) {
    return std::lexicographical_compare(a.point.data(), a.point.data() + dim, b.point.data(), b.point.data() + dim);
  };
  std::sort(out.begin() + static_cast<std::ptrdiff_t>(first), out.end(), less);
  std::size_t kept = first;
  for (std::size_t i = first; i < out.size(); ++i) {
    if (kept > first && out[kept - 1].point == out[i].point)
      out[kept - 1].weight += out[i].weight;
    else
      out[kept++] = out[i];
  }
  out.resize(kept);
}

template <int dim>
void embed_unmerged(const CellTree<dim>& tree, const IVec<dim>& point, double scale,
                    std::vector<NodeWeight<dim>>& out) {
  const CellId<dim> leaf = tree.coarsest_leaf_at(point);
  MPM_VERIFY(leaf.level >= 0, InputError, "adaptive grid: a node outside the domain has no embedding");
  bool real = true;
  for (int a = 0; a < dim; ++a) real = real && on_lattice(point[a], tree.scale(leaf.level));
  if (real) {
    out.push_back({point, leaf.level, scale});
    return;
  }
  // A T-junction or interior point: interpolate in the coarsest leaf; its corners are real or
  // embedded in strictly coarser leaves, so the recursion ends within `levels` steps.
  for_each_corner(tree, leaf.level, leaf.cell, Vec<dim>(point.template cast<double>()), scale,
                  [&](const IVec<dim>& corner, double w) { embed_unmerged(tree, corner, w, out); });
}

}  // namespace

template <int dim>
int home_level(const CellTree<dim>& tree, const IVec<dim>& point) {
  const CellId<dim> leaf = tree.coarsest_leaf_at(point);
  if (leaf.level < 0) return -1;
  for (int a = 0; a < dim; ++a)
    if (!on_lattice(point[a], tree.scale(leaf.level))) return -1;
  return leaf.level;
}

template <int dim>
void embed(const CellTree<dim>& tree, const IVec<dim>& point, double scale, std::vector<NodeWeight<dim>>& out) {
  const std::size_t first = out.size();
  embed_unmerged(tree, point, scale, out);
  merge(out, first);
}

template <int dim>
std::vector<NodeWeight<dim>> basis_in_leaf(const CellTree<dim>& tree, int level, const IVec<dim>& cell,
                                           const Vec<dim>& x) {
  std::vector<NodeWeight<dim>> out;
  const Vec<dim> f = (x - tree.origin()) / tree.dx(tree.finest());
  for_each_corner(tree, level, cell, f, 1.0,
                  [&](const IVec<dim>& corner, double w) { embed_unmerged(tree, corner, w, out); });
  merge(out, 0);
  return out;
}

template <int dim>
std::vector<NodeWeight<dim>> basis_at(const CellTree<dim>& tree, const Vec<dim>& x) {
  const CellId<dim> leaf = tree.leaf_at(x);
  if (leaf.level < 0) return {};
  return basis_in_leaf(tree, leaf.level, leaf.cell, x);
}

#define MPM_INSTANTIATE(dim)                                                                                         \
  template int home_level(const CellTree<dim>&, const IVec<dim>&);                                                   \
  template void embed(const CellTree<dim>&, const IVec<dim>&, double, std::vector<NodeWeight<dim>>&);                \
  template std::vector<NodeWeight<dim>> basis_in_leaf(const CellTree<dim>&, int, const IVec<dim>&, const Vec<dim>&); \
  template std::vector<NodeWeight<dim>> basis_at(const CellTree<dim>&, const Vec<dim>&);
MPM_INSTANTIATE(2)
MPM_INSTANTIATE(3)

}  // namespace mpm::adaptive
