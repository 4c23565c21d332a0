#pragma once
//! The cells of a non-graded adaptive grid (Gao et al. 2017, sec. 5): a forest of quadtrees
//! (2D) or octrees (3D) over a box of level-0 cells, levels n = 0 .. levels-1 with
//! dx_n = dx_0 / 2^n. A cell is refined into its 2^dim children; the leaves tile the domain.
//! Non-graded: a leaf may border leaves any number of levels finer.
//!
//! Only refined cells are stored (one CellSet per level: bit masks of bricks of cells in a hash
//! table): a level-0 cell of the domain is a leaf unless refined, and a child of a refined cell
//! is a leaf unless refined itself. The memory held follows the refined region, not the domain.
//!
//! Coordinates: cell c of level n covers [origin + c dx_n, origin + (c + 1) dx_n). Nodes are
//! named by their coordinate on the finest lattice (spacing dx_{levels-1}), "lattice points".
#include <mpm/adaptive/cell_set.h>
#include <mpm/core/block_table.h>
#include <mpm/core/types.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

namespace mpm::adaptive {

//! The most levels a tree may have (dx_0 / dx_finest = 2^(max_levels - 1)).
inline constexpr int max_levels = 6;

template <int dim>
struct CellId {
  int level = -1;  //!< -1: no cell (outside the domain)
  IVec<dim> cell = IVec<dim>::Zero();
};

template <int dim>
class CellTree {
public:
  CellTree() = default;
  //! A tree of `levels` levels whose level-0 cells (spacing dx0 [m]) tile the box
  //! origin + [0, base_cells) dx0; every cell starts as a level-0 leaf.
  CellTree(const Vec<dim>& origin, const IVec<dim>& base_cells, double dx0, int levels);

  int levels() const { return levels_; }
  int finest() const { return levels_ - 1; }
  double dx(int level) const { return dx0_ / static_cast<double>(1 << level); }
  const Vec<dim>& origin() const { return origin_; }
  const IVec<dim>& base_cells() const { return base_cells_; }
  //! Lattice points per cell edge at `level`: 2^(finest - level).
  int scale(int level) const { return 1 << (finest() - level); }
  //! Position [m] of a lattice point.
  Vec<dim> position(const IVec<dim>& point) const { return origin_ + dx(finest()) * point.template cast<double>(); }

  bool is_refined(int level, const IVec<dim>& cell) const;
  //! True when the cell exists: inside the domain and its parent refined (or level 0).
  bool exists(int level, const IVec<dim>& cell) const;
  bool is_leaf(int level, const IVec<dim>& cell) const { return exists(level, cell) && !is_refined(level, cell); }

  //! Refines a leaf into its 2^dim children (leaves). Throws InputError at the finest level.
  void refine(int level, const IVec<dim>& cell);
  //! Refines the cells that contain x [m] until the leaf there is of level >= `level` (clamped
  //! to the finest); a position outside the domain is left alone.
  void refine_to(const Vec<dim>& x, int level);
  //! Refines, top down, every leaf whose box [lo, hi] gets target_level(lo, hi) > its level
  //! (clamped to the finest level): static refinement near colliders or in user boxes.
  void refine_where(const std::function<int(const Vec<dim>& lo, const Vec<dim>& hi)>& target_level);
  //! refine_where visiting only the level-0 cells that overlap the box [region_lo, region_hi].
  void refine_where(const std::function<int(const Vec<dim>& lo, const Vec<dim>& hi)>& target_level,
                    const Vec<dim>& region_lo, const Vec<dim>& region_hi);

  //! The number of cells refine_where(target_level) would refine, counted without refining;
  //! the count stops as soon as it exceeds `cap` (then returns cap + 1).
  double count_refinements(const std::function<int(const Vec<dim>& lo, const Vec<dim>& hi)>& target_level,
                           double cap) const;
  //! The leaf that contains finest-level cell `f` (level -1 outside the domain).
  CellId<dim> leaf_of(const IVec<dim>& f) const;
  //! The coarsest leaf whose closure contains lattice point `point` (level -1 outside).
  CellId<dim> coarsest_leaf_at(const IVec<dim>& point) const;
  //! The leaf that contains position x [m] (level -1 outside).
  CellId<dim> leaf_at(const Vec<dim>& x) const;
  //! leaf_at(x), or `hint` (a leaf of this tree, or level -1) when it contains x: loops over
  //! particles in storage order pass the previous particle's leaf and seldom read the tables
  //! (the hint's ancestors are refined: the walk starts below the one that holds x).
  CellId<dim> leaf_at(const Vec<dim>& x, const CellId<dim>& hint) const;
  //! The finest level of the leaves that overlap the open box (lo, hi) [m]; -1 when the box
  //! misses the domain.
  int finest_level_in(const Vec<dim>& lo, const Vec<dim>& hi) const;
  //! The same, with the leaf found for the previous box (updated): see leaf_at(x, hint).
  int finest_level_in(const Vec<dim>& lo, const Vec<dim>& hi, CellId<dim>& last_leaf) const;

  //! Calls fn(level, cell) for every leaf, coarse to fine (level-0 leaves in lexicographic order).
  void for_each_leaf(const std::function<void(int, const IVec<dim>&)>& fn) const;
  //! Same domain, levels and refined cells.
  bool operator==(const CellTree& other) const;
  //! Same domain (origin, level-0 cells, dx0) and levels.
  bool same_domain(const CellTree& other) const;
  //! The cells refined in exactly one of the two trees (same_domain required).
  std::vector<CellId<dim>> refined_difference(const CellTree& other) const;
  std::size_t memory_bytes() const;
  //! A cell's coordinates packed into one key (distinct cells of one level, distinct keys).
  static BlockKey key(const IVec<dim>& cell);

private:
  //! Calls fn(cell) for the level-0 cells of the domain that overlap the box [lo, hi].
  template <class Fn>
  void for_each_base_cell(const Vec<dim>& lo, const Vec<dim>& hi, Fn&& fn) const {
    IVec<dim> first, last;
    for (int a = 0; a < dim; ++a) {
      first[a] = std::max(0, static_cast<int>(std::floor(std::max(-1e9, (lo[a] - origin_[a]) / dx0_))));
      last[a] = std::min(base_cells_[a] - 1, static_cast<int>(std::floor(std::min(1e9, (hi[a] - origin_[a]) / dx0_))));
    }
    for_each_in_box<dim>(first, last, fn);
  }
  //! leaf_of(f), the cells of levels below `first_level` that hold f known to be refined.
  CellId<dim> leaf_of(const IVec<dim>& f, int first_level) const;
  void visit_leaves(int level, const IVec<dim>& cell, const std::function<void(int, const IVec<dim>&)>& fn) const;
  //! refine_where's walk, top down over the level-0 cells overlapping [region_lo, region_hi]:
  //! on_refine(level, cell) for each unrefined cell whose target level exceeds its own (false:
  //! stop the walk), then into its children, as into those of every refined cell.
  template <class OnRefine>
  void walk_refinements(const std::function<int(const Vec<dim>&, const Vec<dim>&)>& target_level,
                        const Vec<dim>& region_lo, const Vec<dim>& region_hi, OnRefine&& on_refine) const;
  int finest_level_in(int level, const IVec<dim>& cell, const Vec<dim>& lo, const Vec<dim>& hi) const;

  Vec<dim> origin_ = Vec<dim>::Zero();
  IVec<dim> base_cells_ = IVec<dim>::Zero();
  double dx0_ = 1.0;
  int levels_ = 1;
  std::vector<CellSet<dim>> refined_;  // per level: its refined cells
};

}  // namespace mpm::adaptive
