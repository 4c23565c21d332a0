#pragma once
//! A set of cells of one level of a CellTree: one bit per cell in 64-bit masks of bricks (4^3
//! cells in 3D, 8^2 in 2D), the bricks found through a BlockTable. A query is one hash probe
//! and a bit test; the table holds one entry per brick, so where the set is dense (a tree's
//! refined cells are: they come in bands and regions) it is up to 64 times smaller than a table
//! of the cells and stays in cache. Memory follows the bricks that hold a cell, not the domain.
#include <mpm/core/block_table.h>
#include <mpm/core/types.h>

#include <bit>
#include <cstdint>
#include <vector>

namespace mpm::adaptive {

template <int dim>
class CellSet {
public:
  //! Cell coordinates must lie in [0, 2^21) per axis (a tree holds fewer than 2^20 finest cells
  //! per axis); cells with a negative coordinate are never members.
  bool contains(const IVec<dim>& cell) const {
    if (!(cell.array() >= 0).all()) return false;
    const int slot = table_.find(brick_key(cell));
    return slot >= 0 && ((masks_[static_cast<std::size_t>(slot)] >> bit(cell)) & 1u);
  }
  //! Adds a cell (coordinates >= 0); returns false when it was a member already.
  bool insert(const IVec<dim>& cell) {
    const int slot = table_.insert(brick_key(cell), static_cast<int>(masks_.size()));
    if (static_cast<std::size_t>(slot) == masks_.size()) {
      masks_.push_back(0);
      bricks_.push_back(IVec<dim>(cell.array() / kEdge));
    }
    std::uint64_t& mask = masks_[static_cast<std::size_t>(slot)];
    const std::uint64_t b = std::uint64_t{1} << bit(cell);
    if (mask & b) return false;
    mask |= b;
    ++size_;
    return true;
  }
  //! The number of cells.
  std::size_t size() const { return size_; }
  //! Calls fn(cell) for every member, brick by brick in the order they were first used.
  template <class Fn>
  void for_each(Fn&& fn) const {
    for (std::size_t i = 0; i < masks_.size(); ++i)
      for (std::uint64_t m = masks_[i]; m != 0; m &= m - 1) fn(cell_of(i, std::countr_zero(m)));
  }
  //! Calls fn(cell) for every member of this set that `other` lacks.
  template <class Fn>
  void for_each_not_in(const CellSet& other, Fn&& fn) const {
    for (std::size_t i = 0; i < masks_.size(); ++i) {
      const int slot = other.table_.find(key_of(bricks_[i]));
      const std::uint64_t theirs = slot >= 0 ? other.masks_[static_cast<std::size_t>(slot)] : 0;
      for (std::uint64_t m = masks_[i] & ~theirs; m != 0; m &= m - 1) fn(cell_of(i, std::countr_zero(m)));
    }
  }
  std::size_t bytes() const {
    return table_.bytes() + masks_.capacity() * sizeof(std::uint64_t) + bricks_.capacity() * sizeof(IVec<dim>);
  }

private:
  static constexpr int kShift = dim == 3 ? 2 : 3;  //!< log2 of the brick's edge in cells
  static constexpr int kEdge = 1 << kShift;
  static constexpr int kBits = 21;  //!< bits per axis of a brick key

  static BlockKey key_of(const IVec<dim>& brick) {
    BlockKey k = 0;
    for (int a = dim - 1; a >= 0; --a) k = (k << kBits) | static_cast<BlockKey>(brick[a]);
    return k;
  }
  static BlockKey brick_key(const IVec<dim>& cell) { return key_of(IVec<dim>(cell.array() / kEdge)); }
  static int bit(const IVec<dim>& cell) {
    int b = 0;
    for (int a = dim - 1; a >= 0; --a) b = (b << kShift) | (cell[a] & (kEdge - 1));
    return b;
  }
  IVec<dim> cell_of(std::size_t brick, int b) const {
    IVec<dim> c;
    for (int a = 0; a < dim; ++a, b >>= kShift) c[a] = bricks_[brick][a] * kEdge + (b & (kEdge - 1));
    return c;
  }

  BlockTable table_;                  //!< brick key -> index into masks_ and bricks_
  std::vector<std::uint64_t> masks_;  //!< per brick, bit `bit(cell)` set for its members
  std::vector<IVec<dim>> bricks_;     //!< per brick, its coordinates (cell / kEdge)
  std::size_t size_ = 0;
};

}  // namespace mpm::adaptive
