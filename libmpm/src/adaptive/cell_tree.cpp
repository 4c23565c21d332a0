#include <mpm/adaptive/cell_tree.h>
#include <mpm/core/error.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace mpm::adaptive {

namespace {
constexpr int kBits = 64 / 3;  // bits per axis of a packed cell key (enough for 2D and 3D)
}

template <int dim>
BlockKey CellTree<dim>::key(const IVec<dim>& cell) {
  BlockKey k = 0;
  for (int a = dim - 1; a >= 0; --a) k = (k << kBits) | static_cast<BlockKey>(cell[a]);
  return k;
}

template <int dim>
CellTree<dim>::CellTree(const Vec<dim>& origin, const IVec<dim>& base_cells, double dx0, int levels)
    : origin_(origin), base_cells_(base_cells), dx0_(dx0), levels_(levels) {
  MPM_VERIFY(
      levels >= 1 && levels <= max_levels, InputError,
      "adaptive grid: levels = " + std::to_string(levels) + " is outside [1, " + std::to_string(max_levels) + "]");
  MPM_VERIFY(dx0 > 0.0 && std::isfinite(dx0), InputError, "adaptive grid: the coarsest dx must be > 0");
  for (int a = 0; a < dim; ++a)
    MPM_VERIFY(base_cells[a] >= 1 && (static_cast<double>(base_cells[a]) * (1 << (levels - 1))) < (1 << kBits) / 2.0,
               InputError,
               "adaptive grid: " + std::to_string(base_cells[a]) + " coarse cells on axis " + std::to_string(a) +
                   " with " + std::to_string(levels) + " levels exceed the " + std::to_string((1 << kBits) / 2) +
                   " finest cells per axis that a tree can address");
  refined_.resize(levels);
}

template <int dim>
bool CellTree<dim>::is_refined(int level, const IVec<dim>& cell) const {
  return refined_[level].contains(cell);
}

template <int dim>
bool CellTree<dim>::exists(int level, const IVec<dim>& cell) const {
  if (level < 0 || level >= levels_) return false;
  for (int a = 0; a < dim; ++a)
    if (cell[a] < 0 || cell[a] >= base_cells_[a] << level) return false;
  if (level == 0) return true;
  IVec<dim> parent;
  for (int a = 0; a < dim; ++a) parent[a] = cell[a] >> 1;
  return is_refined(level - 1, parent);
}

template <int dim>
void CellTree<dim>::refine(int level, const IVec<dim>& cell) {
  MPM_VERIFY(level + 1 < levels_, InputError,
             "adaptive grid: a level-" + std::to_string(level) + " cell cannot be refined: the tree has " +
                 std::to_string(levels_) + " levels");
  if (!is_leaf(level, cell)) {
    std::string where;
    for (int a = 0; a < dim; ++a) where += (a ? ", " : "") + std::to_string(cell[a]);
    throw InputError("adaptive grid: level-" + std::to_string(level) + " cell (" + where +
                     ") is not a leaf and cannot be refined");
  }
  refined_[level].insert(cell);
}

template <int dim>
template <class OnRefine>
void CellTree<dim>::walk_refinements(const std::function<int(const Vec<dim>&, const Vec<dim>&)>& target_level,
                                     const Vec<dim>& region_lo, const Vec<dim>& region_hi, OnRefine&& on_refine) const {
  bool go_on = true;
  std::function<void(int, const IVec<dim>&)> visit = [&](int level, const IVec<dim>& cell) {
    if (!is_refined(level, cell)) {
      if (level == finest()) return;
      const Vec<dim> lo = origin_ + dx(level) * cell.template cast<double>();
      const Vec<dim> hi = lo + Vec<dim>::Constant(dx(level));
      if (target_level(lo, hi) <= level) return;
      go_on = on_refine(level, cell);
    }
    for (int c = 0; c < (1 << dim) && go_on; ++c) {
      IVec<dim> child;
      for (int a = 0; a < dim; ++a) child[a] = 2 * cell[a] + ((c >> a) & 1);
      visit(level + 1, child);
    }
  };
  for_each_base_cell(region_lo, region_hi, [&](const IVec<dim>& cell) {
    if (go_on) visit(0, cell);
  });
}

template <int dim>
void CellTree<dim>::refine_where(const std::function<int(const Vec<dim>&, const Vec<dim>&)>& target_level,
                                 const Vec<dim>& region_lo, const Vec<dim>& region_hi) {
  walk_refinements(target_level, region_lo, region_hi, [&](int level, const IVec<dim>& cell) {
    refine(level, cell);
    return true;
  });
}

template <int dim>
double CellTree<dim>::count_refinements(const std::function<int(const Vec<dim>&, const Vec<dim>&)>& target_level,
                                        double cap) const {
  double count = 0.0;
  walk_refinements(target_level, origin_, origin_ + dx0_ * base_cells_.template cast<double>(),
                   [&](int, const IVec<dim>&) { return ++count <= cap; });
  return count;
}

template <int dim>
void CellTree<dim>::refine_where(const std::function<int(const Vec<dim>&, const Vec<dim>&)>& target_level) {
  refine_where(target_level, origin_, origin_ + dx0_ * base_cells_.template cast<double>());
}

template <int dim>
void CellTree<dim>::refine_to(const Vec<dim>& x, int level) {
  CellId<dim> leaf = leaf_at(x);
  while (leaf.level >= 0 && leaf.level < std::min(level, finest())) {
    refine(leaf.level, leaf.cell);
    leaf = leaf_at(x);
  }
}

template <int dim>
CellId<dim> CellTree<dim>::leaf_of(const IVec<dim>& f) const {
  return leaf_of(f, 0);
}

template <int dim>
CellId<dim> CellTree<dim>::leaf_of(const IVec<dim>& f, int first_level) const {
  for (int a = 0; a < dim; ++a)
    if (f[a] < 0 || f[a] >= base_cells_[a] << finest()) return {};
  for (int level = first_level; level < levels_; ++level) {
    IVec<dim> cell;
    for (int a = 0; a < dim; ++a) cell[a] = f[a] >> (finest() - level);
    if (level == finest() || !is_refined(level, cell)) return {level, cell};
  }
  return {};
}

template <int dim>
CellId<dim> CellTree<dim>::coarsest_leaf_at(const IVec<dim>& point) const {
  // Level by level from the coarsest: the 2^dim finest cells around the point lie in at most
  // 2^dim cells of each level; the first of them that is not refined is the coarsest leaf
  // (all of them exist, since every coarser one was refined).
  IVec<dim> around[1 << dim];
  int count = 0;
  for (int corner = 0; corner < (1 << dim); ++corner) {
    IVec<dim> f = point;
    bool inside = true;
    for (int a = 0; a < dim; ++a) {
      f[a] -= (corner >> a) & 1;
      inside = inside && f[a] >= 0 && f[a] < base_cells_[a] << finest();
    }
    if (inside) around[count++] = f;
  }
  for (int level = 0; level <= finest() && count > 0; ++level) {
    IVec<dim> seen[1 << dim];
    int distinct = 0;
    for (int i = 0; i < count; ++i) {
      IVec<dim> cell;
      for (int a = 0; a < dim; ++a) cell[a] = around[i][a] >> (finest() - level);
      bool repeated = false;
      for (int j = 0; j < distinct && !repeated; ++j) repeated = seen[j] == cell;
      if (repeated) continue;
      seen[distinct++] = cell;
      if (level == finest() || !is_refined(level, cell)) return {level, cell};
    }
  }
  return {};
}

template <int dim>
CellId<dim> CellTree<dim>::leaf_at(const Vec<dim>& x) const {
  return leaf_at(x, CellId<dim>{});
}

template <int dim>
CellId<dim> CellTree<dim>::leaf_at(const Vec<dim>& x, const CellId<dim>& hint) const {
  const Vec<dim> f = (x - origin_) / dx(finest());
  IVec<dim> cell;
  for (int a = 0; a < dim; ++a) {
    if (!(std::abs(f[a]) < 1e9)) return {};
    cell[a] = static_cast<int>(std::floor(f[a]));
  }
  // The finest level on which x's cell is the hint's or one of its ancestors (cells outside
  // the domain, negative, never match): the hint itself, or a refined cell (an ancestor of a
  // leaf) below which the walk starts.
  int level = hint.level;
  for (; level >= 0; --level) {
    bool same = true;
    for (int a = 0; a < dim && same; ++a) same = cell[a] >> (finest() - level) == hint.cell[a] >> (hint.level - level);
    if (same) break;
  }
  return level >= 0 && level == hint.level ? hint : leaf_of(cell, level + 1);
}

template <int dim>
int CellTree<dim>::finest_level_in(int level, const IVec<dim>& cell, const Vec<dim>& lo, const Vec<dim>& hi) const {
  const Vec<dim> cell_lo = origin_ + dx(level) * cell.template cast<double>();
  for (int a = 0; a < dim; ++a)
    if (!(cell_lo[a] < hi[a] && cell_lo[a] + dx(level) > lo[a])) return -1;
  if (!is_refined(level, cell)) return level;
  int finest_found = -1;
  for (int c = 0; c < (1 << dim) && finest_found < finest(); ++c) {
    IVec<dim> child;
    for (int a = 0; a < dim; ++a) child[a] = 2 * cell[a] + ((c >> a) & 1);
    finest_found = std::max(finest_found, finest_level_in(level + 1, child, lo, hi));
  }
  return finest_found;
}

template <int dim>
int CellTree<dim>::finest_level_in(const Vec<dim>& lo, const Vec<dim>& hi) const {
  CellId<dim> none;
  return finest_level_in(lo, hi, none);
}

template <int dim>
int CellTree<dim>::finest_level_in(const Vec<dim>& lo, const Vec<dim>& hi, CellId<dim>& last_leaf) const {
  // The leaf at the box's centre is the answer when it is of the finest level, or when the box
  // keeps clear of its faces by more than the rounding of the walk below (most particles' boxes,
  // their own sub-cells, do one or the other).
  const CellId<dim> leaf = last_leaf = leaf_at(0.5 * (lo + hi), last_leaf);
  if (leaf.level >= 0) {
    if (leaf.level == finest()) return leaf.level;
    const Vec<dim> leaf_lo = origin_ + dx(leaf.level) * leaf.cell.template cast<double>();
    bool inside = true;
    for (int a = 0; a < dim && inside; ++a) {
      const double margin = 1e-12 * dx(finest()) +
                            16 * std::numeric_limits<double>::epsilon() * std::max(std::abs(lo[a]), std::abs(hi[a]));
      inside = lo[a] > leaf_lo[a] + margin && hi[a] < leaf_lo[a] + dx(leaf.level) - margin;
    }
    if (inside) return leaf.level;
  }
  int finest_found = -1;
  for_each_base_cell(lo, hi, [&](const IVec<dim>& cell) {
    if (finest_found < finest()) finest_found = std::max(finest_found, finest_level_in(0, cell, lo, hi));
  });
  return finest_found;
}

template <int dim>
void CellTree<dim>::visit_leaves(int level, const IVec<dim>& cell,
                                 const std::function<void(int, const IVec<dim>&)>& fn) const {
  if (!is_refined(level, cell)) {
    fn(level, cell);
    return;
  }
  for (int c = 0; c < (1 << dim); ++c) {
    IVec<dim> child;
    for (int a = 0; a < dim; ++a) child[a] = 2 * cell[a] + ((c >> a) & 1);
    visit_leaves(level + 1, child, fn);
  }
}

template <int dim>
void CellTree<dim>::for_each_leaf(const std::function<void(int, const IVec<dim>&)>& fn) const {
  for_each_base_cell(origin_, origin_ + dx0_ * base_cells_.template cast<double>(),
                     [&](const IVec<dim>& cell) { visit_leaves(0, cell, fn); });
}

template <int dim>
bool CellTree<dim>::operator==(const CellTree& other) const {
  if (!same_domain(other)) return false;
  for (int l = 0; l < levels_; ++l) {
    if (refined_[l].size() != other.refined_[l].size()) return false;
    bool same = true;
    refined_[l].for_each_not_in(other.refined_[l], [&](const IVec<dim>&) { same = false; });
    if (!same) return false;
  }
  return true;
}

template <int dim>
bool CellTree<dim>::same_domain(const CellTree& other) const {
  return origin_ == other.origin_ && base_cells_ == other.base_cells_ && dx0_ == other.dx0_ && levels_ == other.levels_;
}

template <int dim>
std::vector<CellId<dim>> CellTree<dim>::refined_difference(const CellTree& other) const {
  MPM_VERIFY(same_domain(other), InputError, "adaptive grid: trees of different domains or levels");
  std::vector<CellId<dim>> out;
  auto unmatched = [&](const CellTree& a, const CellTree& b) {
    for (int l = 0; l < levels_; ++l)
      a.refined_[l].for_each_not_in(b.refined_[l], [&](const IVec<dim>& cell) { out.push_back({l, cell}); });
  };
  unmatched(*this, other);
  unmatched(other, *this);
  return out;
}

template <int dim>
std::size_t CellTree<dim>::memory_bytes() const {
  std::size_t bytes = 0;
  for (const CellSet<dim>& s : refined_) bytes += s.bytes();
  return bytes;
}

template class CellTree<2>;
template class CellTree<3>;

}  // namespace mpm::adaptive
