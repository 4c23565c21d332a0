#pragma once
//! A sparse background grid: nodes are grouped in blocks of B^dim (B = 4 in 3D, 8 in 2D, 64
//! nodes either way) and only blocks touched by a particle stencil are allocated. A hash
//! table (BlockTable) maps packed block coordinates to storage, so the memory held follows the
//! allocated blocks, not the domain. The adaptive grid (mpm/adaptive/) is a stack of these, one
//! per level with dx_n = dx_0 / 2^n (Gao et al. 2017, sec. 6.1).
//!
//! Node channels are structure-of-arrays over all allocated nodes: node n of block b is at
//! b * nodes_per_block + n. Channels a scene does not use stay empty (lean scenes).
//!
//! Periodic axes: the domain [lo, hi) holds N = (hi - lo) / dx cells and node j + N is node j.
//! The grid keeps `periodic_margin` ghost nodes beyond both ends of such an axis, so that the
//! stencil of every particle in [lo, hi) stays inside the grid; a ghost's canonical node
//! (periodic_image) lies in [lo, hi). The allocated set is closed under images: activate() adds
//! the block of the image of every allocated ghost node, so that the periodic stages
//! (stages/periodic_boundary.h) can fold ghosts onto their images and fill them back.
#include <mpm/core/block_table.h>
#include <mpm/core/types.h>

#include <array>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace mpm {

template <int dim>
class SparseGrid {
public:
  static constexpr int block_bits = dim == 3 ? 2 : 3;
  static constexpr int block_size = 1 << block_bits;  //!< B nodes per axis
  static constexpr int nodes_per_block = ipow(block_size, dim);

  //! Ghost nodes beyond each end of a periodic axis: covers the widest kernel (cubic B-spline,
  //! nodes floor(xi) - 1 .. floor(xi) + 2 for xi in [0, N)).
  static constexpr int periodic_margin = 3;

  SparseGrid() = default;
  //! Grid covering the box [lo, hi] with spacing dx [m]; nodes at lo + i dx, and on the axes
  //! with `periodic` set, (hi - lo) / dx whole cells and periodic_margin ghost nodes each side.
  SparseGrid(const Vec<dim>& lo, const Vec<dim>& hi, double dx, const std::array<bool, dim>& periodic = {});

  double dx() const { return dx_; }
  const Vec<dim>& origin() const { return origin_; }
  const IVec<dim>& node_counts() const { return node_counts_; }  //!< nodes per axis
  const IVec<dim>& block_counts() const { return block_counts_; }

  //! Cells per period along each axis, 0 on the axes that are not periodic.
  const IVec<dim>& period() const { return period_; }
  bool is_periodic() const { return (period_.array() > 0).any(); }
  //! First canonical node per axis: periodic_margin on periodic axes, 0 elsewhere.
  IVec<dim> periodic_lo() const {
    return (period_.array() > 0).select(IVec<dim>::Constant(periodic_margin), IVec<dim>::Zero());
  }
  //! The canonical node of `node`: wrapped into [periodic_lo, periodic_lo + period) on periodic
  //! axes, unchanged elsewhere.
  IVec<dim> periodic_image(IVec<dim> node) const {
    for (int a = 0; a < dim; ++a)
      if (period_[a] > 0) {
        const int j = (node[a] - periodic_margin) % period_[a];
        node[a] = periodic_margin + (j < 0 ? j + period_[a] : j);
      }
    return node;
  }

  //! Bits per axis of a packed block key; the last axis is the most significant, so keys sort
  //! like the blocks' lexicographic order (last axis slowest).
  static constexpr int key_bits = 64 / dim;

  //! Key of the block containing node `node` (node coordinates >= 0).
  BlockKey block_id(const IVec<dim>& node) const {
    BlockKey key = 0;
    for (int a = dim - 1; a >= 0; --a) key = (key << key_bits) | static_cast<BlockKey>(node[a] >> block_bits);
    return key;
  }
  IVec<dim> block_coord(BlockKey key) const {
    IVec<dim> c;
    for (int a = 0; a < dim; ++a) {
      c[a] = static_cast<int>(key & ((BlockKey{1} << key_bits) - 1));
      key >>= key_bits;
    }
    return c;
  }

  //! Replaces the allocated set by the given block keys (sorted, unique), plus on a periodic
  //! grid the blocks of the images of their ghost nodes, and zeroes mass and velocity; other
  //! channels are (re)allocated on request.
  void activate(const std::vector<BlockKey>& block_ids);
  //! Storage slot of block `key`, or -1 when it is not allocated.
  int slot(BlockKey key) const { return slot_.find(key); }
  int block_count() const { return static_cast<int>(active_.size()); }
  BlockKey active_block_id(int s) const { return active_[s]; }
  //! The allocated blocks, by storage slot.
  const std::vector<BlockKey>& active_blocks() const { return active_; }
  //! Bytes held by the block table and the node channels: proportional to the allocated blocks.
  std::size_t memory_bytes() const;
  std::size_t node_storage() const { return mass.size(); }

  //! Integer coordinate and position of storage node k.
  IVec<dim> node_coord(std::size_t k) const;
  Vec<dim> node_position(std::size_t k) const { return origin_ + dx_ * node_coord(k).template cast<double>(); }
  //! Storage index of integer node `node`, or -1 if its block is not allocated.
  Index node_index(const IVec<dim>& node) const;
  //! Position of a node within its block's storage: node_index = slot * nodes_per_block + this.
  static int local_index(const IVec<dim>& node) {
    int local = 0;
    for (int a = dim - 1; a >= 0; --a) local = (local << block_bits) | (node[a] & (block_size - 1));
    return local;
  }

  std::vector<std::pair<std::string, std::size_t>> memory_per_field() const;

  // Node channels.
  std::vector<double> mass;            //!< [kg]
  std::vector<Vec<dim>> velocity;      //!< momentum after P2G, velocity after normalisation [m/s]
  std::vector<Vec<dim>> velocity_old;  //!< velocity before forces (FLIP only)
  std::vector<Vec<dim>> force;         //!< internal force [N] (solid only)

private:
  double dx_ = 1.0;
  Vec<dim> origin_ = Vec<dim>::Zero();
  IVec<dim> node_counts_ = IVec<dim>::Zero();
  IVec<dim> block_counts_ = IVec<dim>::Zero();
  IVec<dim> period_ = IVec<dim>::Zero();
  BlockTable slot_;               // block key -> storage slot
  std::vector<BlockKey> active_;  // storage slot -> block key
};

}  // namespace mpm
