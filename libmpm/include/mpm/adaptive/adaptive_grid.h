#pragma once
//! The multi-level sparse grid of adaptive GIMP and its ghost nodes (Gao et al. 2017, sec. 6.1,
//! eq. 15, Fig. 10).
//!
//! One SparseGrid per level n (dx_n = dx_0 / 2^n) over the whole domain; each holds
//!  - the real nodes whose home is level n (constrained_basis.h), and
//!  - ghost nodes: level-n nodes of particle stencils that are not real on level n (points
//!    embedded in coarser leaves, or real nodes of another level).
//! Every particle transfers with uniform GIMP weights on one level: the finest level of the
//! leaves its box overlaps, where the constrained basis restricted to the box is exactly the
//! level's multilinear interpolant. After P2G each ghost's sums are pushed to its real nodes
//! with the embedding weights (w_ip = sum_k E_ik w_kp, eq. 15) and the ghost is cleared;
//! before G2P each ghost is pulled back from them. Grid updates (forces, walls, colliders)
//! then run on every level as on a uniform grid: ghosts hold no mass.
//!
//! prepare() allocates, per level, the blocks of the stencils of the particles that transfer
//! there and the blocks of the real nodes their ghosts reach, and builds the ghost tables of
//! the nodes the stencils reach (in a thin fine band, about a quarter of the blocks' nodes that
//! are not real). Memory and time follow the particles' stencils, not the domain. Between steps
//! it keeps what still holds: the node statuses of the blocks a tree change cannot reach, the
//! grids while neither the tree nor the blocks change, and the ghost tables while they also
//! hold every node reached.
#include <mpm/adaptive/cell_tree.h>
#include <mpm/adaptive/constrained_basis.h>
#include <mpm/core/error.h>
#include <mpm/core/kernels.h>
#include <mpm/core/particle_buckets.h>
#include <mpm/core/sparse_grid.h>

#include <array>
#include <bit>
#include <cstdint>
#include <limits>
#include <tuple>
#include <vector>

#include <tbb/parallel_for.h>

namespace mpm::adaptive {

//! Uniform GIMP weights along one axis for any particle half-size h (in cells of the level):
//! w(r) = (H(r + h) - H(r - h)) / (2h), dw/dr = (N1(r + h) - N1(r - h)) / (2h) (Gao et al.
//! 2017, eq. 5-6; H the antiderivative of the hat N1), on the nodes base .. base + count - 1,
//! the nodes j with |xi - j| < 1 + h (at most ceil(2h) + 2): the quadratic B-spline stencil
//! at h = 1/2, wider for a coarse particle transferring on a finer level.
struct GimpAxis {
  static constexpr int max_count = 2 * (1 << (max_levels - 1)) + 2;
  int base = 0;
  int count = 0;
  double w[max_count];
  double dw[max_count];  //!< dw/dr, per cell
  void compute(double xi, double h);
};

//! A ghost's link to one real node: value_ghost += weight * value(level, index). APIC's affine
//! terms take the offset x_i - x_k from the two nodes' positions (link_offset): stored, it
//! tripled the tables (24 of 40 bytes per link). 16 bytes: a level's storage index fits in 32
//! bits (prepare() checks).
template <int dim>
struct GhostLink {
  std::uint32_t index;
  int level;
  double weight;
};
static_assert(sizeof(GhostLink<3>) == 16);

template <int dim>
class AdaptiveGrid {
public:
  AdaptiveGrid() = default;
  //! `points_per_axis` k: particles are seeded k per axis per cell of their level.
  explicit AdaptiveGrid(CellTree<dim> tree, int points_per_axis = 2);

  const CellTree<dim>& tree() const { return tree_; }
  //! The tree, for refinement; call prepare() before the next transfer.
  CellTree<dim>& tree() { return tree_; }
  int levels() const { return tree_.levels(); }
  SparseGrid<dim>& level(int n) { return levels_[n]; }
  const SparseGrid<dim>& level(int n) const { return levels_[n]; }

  //! Side [m] of the GIMP box of a particle of type (level) q: its own sub-cell, dx_q / k. The
  //! boxes tile the body across levels (a coarse particle's box is the union of the fine ones
  //! it was merged from), so the particles are a consistent quadrature everywhere: with boxes
  //! of one cell (dx_q, the quadratic B-spline) they would overlap unevenly at a level jump, a
  //! first-order error (test_vibrating_bar measures both).
  double particle_size(int type) const { return tree_.dx(type) / points_per_axis_; }
  int points_per_axis() const { return points_per_axis_; }
  //! The uniform weights of a particle on its own level: uGIMP with h = 1 / (2k) (the quadratic
  //! B-spline for k = 1). The regular particles of type n on level n transfer with them.
  Kernel regular_kernel() const {
    if (points_per_axis_ == 1) return QuadraticBSpline{};
    return UGimp{0.5 / points_per_axis_};
  }
  //! The type whose GIMP box is one cell of level n (k = 2^m points per axis: type n - m), or
  //! -1 when there is none other than n itself.
  int cell_box_type(int n) const {
    const int m = std::countr_zero(static_cast<unsigned>(points_per_axis_));
    return points_per_axis_ > 1 && std::has_single_bit(static_cast<unsigned>(points_per_axis_)) && n >= m ? n - m : -1;
  }

  //! Finds the transfer level of every particle (positions x, types `type`), allocates the
  //! level grids and builds the ghost tables. Throws NumericalError naming `stage` for a
  //! particle that is not finite or whose stencil leaves the grid. When the particles' storage
  //! is scattered against the transfer order (level 0's buckets, ..., the finest level's, then
  //! the irregular particles) and `move` is given, calls move(order) for the caller to store
  //! them anew in that order (new index i holds old index order[i]; the transfers reach them
  //! through the buckets, and resampling appends and removes particles anywhere), renumbers
  //! its own tables and returns true.
  bool prepare(const std::vector<Vec<dim>>& x, const std::vector<std::uint16_t>& type,
               const std::string& stage = "prepare", const MoveParticles& move = {});
  std::size_t particle_count() const { return class_.size(); }
  //! The particles that transfer on a level as on a uniform grid (regular), in two groups per
  //! level n, with 3^dim stencils inside the level: group 2n, the particles of type n, with
  //! regular_kernel(); group 2n + 1, those whose GIMP box is one cell of level n (the type
  //! log2 k levels coarser, for k = 2, 4, ... points per axis), with the quadratic B-spline,
  //! which is uGIMP for a box of one cell (empty for other k). The uniform loops (transfer.h)
  //! serve them, in parallel.
  static constexpr int groups_per_level = 2;
  int regular_groups() const { return groups_per_level * levels(); }
  static int group_level(int group) { return group / groups_per_level; }
  Kernel group_kernel(int group) const {
    return group % groups_per_level == 0 ? regular_kernel() : Kernel{QuadraticBSpline{}};
  }
  const ParticleBuckets<dim>& regular(int group) const { return regular_[group]; }
  //! The regular particles of a group whose stencil holds an embedded ghost, in their buckets:
  //! APIC adds the ghosts' affine terms for them beside the uniform loops (adaptive_transfer.h).
  const ParticleBuckets<dim>& near_embedded(int group) const { return near_embedded_[group]; }
  //! Per entry of near_embedded(group).particle: which nodes of its stencil are embedded
  //! ghosts, bit i_0 + 3 i_1 (+ 9 i_2) for node uniform_base() + (i_0, i_1, i_2) (the offsets
  //! of bit j: stencil_offsets[j]). The ghosts' APIC terms visit only these nodes.
  const std::vector<std::uint32_t>& near_embedded_masks(int group) const { return near_masks_[group]; }
  //! The node offsets (i_0, i_1, i_2) of bit j of a stencil mask.
  static constexpr auto stencil_offsets = [] {
    std::array<std::array<std::int8_t, 3>, 27> offsets{};
    for (int j = 0; j < 27; ++j)
      offsets[j] = {static_cast<std::int8_t>(j % 3), static_cast<std::int8_t>(j / 3 % 3),
                    static_cast<std::int8_t>(j / 9)};
    return offsets;
  }();
  //! The other particles: they take the general path (for_each_weight). Ordered by transfer
  //! level and block of their first stencil node, in groups of one (level, block).
  const std::vector<std::uint32_t>& irregular() const { return irregular_; }
  //! The groups of irregular() (group g: entries begin[g] .. begin[g + 1] - 1) by colour: the
  //! stencils of two groups of one colour share no node, so a colour scatters in parallel.
  struct IrregularGroups {
    std::vector<std::uint32_t> begin{0};
    std::vector<std::vector<int>> by_color;
  };
  const IrregularGroups& irregular_groups() const { return irregular_groups_; }
  //! Transfer level of particle p (after prepare).
  int transfer_level(std::size_t p) const { return class_[p].level; }
  //! Half-size of particle p's GIMP box in cells of its transfer level (after prepare).
  double half_cells(std::size_t p) const { return half_cells_[class_[p].type * max_levels + class_[p].level]; }

  //! Calls fn(k, w, grad_w, x_k) for the level-n storage node k of every non-zero weight of a
  //! particle at x that transfers on level n with half-size h cells: w = w_kp (uniform GIMP),
  //! grad_w [1/m], x_k the node's position [m].
  template <class Fn>
  void for_each_weight(int n, double h, const Vec<dim>& x, Fn&& fn) const {
    GimpAxis axis[dim];
    axis_weights(n, h, x, axis);
    for_each_weight(n, axis, fn);
  }
  //! The same from the 1D weights axis_weights() gave, for a caller that reads them too.
  template <class Fn>
  void for_each_weight(int n, const GimpAxis* axis, Fn&& fn) const;
  //! First node of the 3^dim stencil of regular_kernel() at x on level n: the expression of
  //! the uniform loops (CellMap, then floor(xi - 1/2)).
  IVec<dim> uniform_base(int n, const Vec<dim>& x) const {
    const SparseGrid<dim>& g = levels_[n];
    const double inv_dx = 1.0 / g.dx();
    IVec<dim> base;
    for (int a = 0; a < dim; ++a) base[a] = static_cast<int>(std::floor((x[a] - g.origin()[a]) * inv_dx - 0.5));
    return base;
  }
  //! The 1D weights of every axis for that particle: prepare() and for_each_weight() share this
  //! one expression, so they see the same stencil.
  void axis_weights(int n, double h, const Vec<dim>& x, GimpAxis* axis) const {
    const SparseGrid<dim>& g = levels_[n];
    const double inv_dx = 1.0 / g.dx();  // CellMap's expression: the uniform loops' stencil
    for (int a = 0; a < dim; ++a) axis[a].compute((x[a] - g.origin()[a]) * inv_dx, h);
  }

  //! Ghosts of level n: storage index, first link (CSR), and the second moment of their
  //! links R_k = sum_i E_ik (x_i - x_k)(x_i - x_k)^T [m^2] that APIC's D_p needs.
  struct Ghosts {
    std::vector<Index> node;
    std::vector<std::uint32_t> begin{0};
    std::vector<GhostLink<dim>> link;
    //! Per ghost: its row in spread and velocity_moment when it is embedded, -1 when it is a
    //! real node of another level (one link of weight 1 at its own position: both vanish).
    std::vector<int> moment;
    //! R_k of the embedded ghosts, symmetric: its upper triangle row by row (spread_of()).
    std::vector<std::array<double, dim*(dim + 1) / 2>> spread;
    Mat<dim> spread_of(int m) const {
      Mat<dim> R;
      for (int a = 0, e = 0; a < dim; ++a)
        for (int b = a; b < dim; ++b, ++e) R(a, b) = R(b, a) = spread[static_cast<std::size_t>(m)][e];
      return R;
    }
    //! Per storage block: bit l set when node l of the block is a ghost, and the index of the
    //! block's first ghost. A block's ghosts are consecutive and in node order, so a node's
    //! ghost index is the first's plus the count of ghosts before it (12 bytes per block, not
    //! an int per node).
    std::vector<std::uint64_t> block_mask;
    std::vector<std::uint32_t> block_first;
    //! The ghost index of storage node k, or -1.
    int of_node(Index k) const {
      constexpr int nodes = SparseGrid<dim>::nodes_per_block;
      static_assert(nodes <= 64);
      const auto block = static_cast<std::size_t>(k / nodes);
      const int local = static_cast<int>(k % nodes);
      const std::uint64_t mask = block_mask[block];
      if ((mask >> local & 1) == 0) return -1;
      return static_cast<int>(block_first[block]) + std::popcount(mask & ((std::uint64_t{1} << local) - 1));
    }
    //! Q_k = sum_i E_ik v_i (x_i - x_k)^T [m^2/s], filled by pull_velocity for APIC's B_p.
    std::vector<Mat<dim>> velocity_moment;
  };
  const Ghosts& ghosts(int n) const { return ghosts_[n]; }

  //! Position [m] of storage node k of level n.
  Vec<dim> node_position(int n, Index k) const { return levels_[n].node_position(static_cast<std::size_t>(k)); }
  //! x_i - x_k [m] of a link of a ghost at x_k [m].
  Vec<dim> link_offset(const GhostLink<dim>& link, const Vec<dim>& x_k) const {
    return node_position(link.level, link.index) - x_k;
  }

  //! target(level, index) += sum over ghosts of weight * ghost value, then ghost value = 0, for
  //! a channel given as one vector per level (forces: f_i = sum_k E_ik f_k).
  template <class T>
  void push(std::vector<std::vector<T>*> channel) const;
  //! One node channel of every level, for push(): per_level(&SparseGrid<dim>::force).
  template <class T>
  std::vector<std::vector<T>*> per_level(std::vector<T> SparseGrid<dim>::*field) {
    std::vector<std::vector<T>*> channel;
    for (SparseGrid<dim>& g : levels_) channel.push_back(&(g.*field));
    return channel;
  }
  //! Pushes the ghosts' mass and APIC momentum to the real nodes: (m v)_i += E_ik ((m v)_k +
  //! G_k (x_i - x_k)) with G_k = sum_p w_kp m_p C_p (`affine`, one per ghost), which makes the
  //! momentum that of the real node's own position x_i (so P2G reproduces affine fields and
  //! conserves angular momentum); mass and momentum of the ghosts are cleared.
  void push_momentum(const std::vector<std::vector<Mat<dim>>>& affine);
  //! Fills the ghosts' velocity (and velocity_old when `old`) and velocity moment Q_k from the
  //! real nodes: after the grid update, before G2P.
  void pull_velocity(bool old);

  //! Memory held [B]: the level grids' fields plus index_bytes().
  std::size_t memory_bytes() const;
  //! Memory of everything but the level grids' fields [B]: tree, ghost tables, transfer lists.
  std::size_t index_bytes() const;

private:
  CellTree<dim> tree_;
  int points_per_axis_ = 2;
  std::vector<SparseGrid<dim>> levels_;
  std::vector<Ghosts> ghosts_;
  // The ghosts' links by the real node they reach, per level of that node: push() and
  // push_momentum() gather each real node's sums in parallel, in the order (ghost level,
  // ghost, link) a serial scatter would add them (bit for bit the same result).
  struct PushSource {  // 8 bytes (build_push_tables() checks the ghosts' count)
    std::uint32_t level : 3, ghost : 29;
    std::uint32_t link;
  };
  static_assert(sizeof(PushSource) == 8 && max_levels <= 8);
  struct PushTable {
    std::vector<Index> target;         // real node of each segment
    std::vector<std::uint32_t> begin;  // segment s: source[begin[s]] .. source[begin[s + 1] - 1]
    std::vector<PushSource> source;
  };
  std::vector<PushTable> push_tables_;
  void build_push_tables();
  //! fn(level m, real node i, sources) for every real node a ghost reaches, in parallel.
  template <class Fn>
  void for_each_push_target(Fn&& fn) const;
  //! Sets every ghost's value to zero in each level's `channel`.
  template <class T>
  void clear_ghosts(const std::vector<std::vector<T>*>& channel) const;
  // Per particle: its transfer level (-1 before it is reported as outside the grid) and its
  // type (level) at prepare(), in one byte.
  struct ParticleClass {
    std::int8_t level : 4;
    std::int8_t type : 4;
  };
  static_assert(sizeof(ParticleClass) == 1 && max_levels <= 7);
  std::vector<ParticleClass> class_;
  // Half-size of a particle of type t in cells of level n: half_cells_[t * max_levels + n].
  std::array<double, max_levels * max_levels> half_cells_{};
  std::vector<ParticleBuckets<dim>> regular_;
  std::vector<std::uint32_t> irregular_;
  IrregularGroups irregular_groups_;
  //! Fills irregular_ and irregular_groups_ from (level, first block, particle) triples.
  void group_irregular(std::vector<std::tuple<int, BlockKey, std::uint32_t>>& at, int span);
  std::vector<ParticleBuckets<dim>> near_embedded_;
  std::vector<std::vector<std::uint32_t>> near_masks_;
  //! prepare()'s move: stores the particles in transfer order when they are scattered.
  bool store_in_transfer_order(const MoveParticles& move);

  // Node statuses per block for the tree status_tree_; a tree change keeps those of the blocks
  // it cannot reach (forget_changed_statuses()).
  struct PendingGhost {
    IVec<dim> node;  // level coordinate
    std::uint32_t first_link, end_link;
  };
  struct BlockStatus {
    std::uint32_t first_ghost, end_ghost;
    std::uint64_t embedded;  // bit l: node l of the block is an embedded ghost
    std::uint64_t known;     // bit l: node l's status is here (the nodes reached so far)
    std::uint32_t first_reached, end_reached;
    // Lattice box of every point the statuses were read from (the nodes and their links): a
    // tree change away from it leaves them as they are (forget_changed_statuses).
    IVec<dim> depends_lo, depends_hi;
  };
  // A ghost's link as its status keeps it: the real node's lattice point and home level packed
  // in 64 bits (the links are most of the statuses: 16 bytes instead of NodeWeight's 24).
  struct StatusLink {
    static constexpr int level_bits = 4, point_bits = (64 - level_bits) / dim;
    std::uint64_t key;
    double weight;
    static StatusLink pack(const NodeWeight<dim>& link);
    NodeWeight<dim> unpack() const;
  };
  static_assert(sizeof(StatusLink) == 16 && max_levels <= 1 << StatusLink::level_bits);
  struct LevelStatus {
    BlockTable index;  // block key -> blocks[]
    std::vector<BlockStatus> blocks;
    std::vector<PendingGhost> ghosts;
    std::vector<StatusLink> links;
    std::vector<std::pair<int, BlockKey>> reached;  // (level, block) of a block's ghosts' links
    std::size_t unused = 0;                         // ghosts of entries a block no longer uses
  };
  struct FreshStatus {  // one block's status before it joins its level's tables
    std::uint64_t embedded = 0;
    IVec<dim> depends_lo = IVec<dim>::Constant(std::numeric_limits<int>::max()),
              depends_hi = IVec<dim>::Constant(std::numeric_limits<int>::min());
    std::vector<PendingGhost> ghosts;  // links relative to `links`
    std::vector<NodeWeight<dim>> links;
    std::vector<std::pair<int, BlockKey>> reached;
  };
  //! The status of the nodes `nodes` (bit local_index) of block `key` of level n under the
  //! current tree.
  FreshStatus block_status(int n, BlockKey key, std::uint64_t nodes) const;
  CellTree<dim> status_tree_;
  std::vector<LevelStatus> status_;
  //! After a tree change: drops the statuses the change can reach and those of unused blocks;
  //! also when the unused entries have grown (statuses_stale_).
  void forget_changed_statuses();
  bool statuses_stale_ = false;
  std::vector<std::vector<BlockKey>> own_blocks_;  // per level: the blocks of the ghost tables
  //! Per block of own (sorted) of level n, the nodes the particles' stencils on level n reach
  //! (bit local_index): the ghosts a table needs; the others receive and give nothing.
  //! base_in_block: per particle, its regular stencil's first node in its bucket's block
  //! (packed by prepare()), read for the regular particles.
  std::vector<std::uint64_t> stencil_nodes(int n, const std::vector<Vec<dim>>& x,
                                           const std::vector<std::uint8_t>& base_in_block,
                                           const std::vector<BlockKey>& own) const;
  std::vector<std::vector<std::uint64_t>> tabled_;  // per level and own block: the tabled nodes
};

template <int dim>
template <class Fn>
void AdaptiveGrid<dim>::for_each_weight(int n, const GimpAxis* axis, Fn&& fn) const {
  const SparseGrid<dim>& g = levels_[n];
  const double inv_dx = 1.0 / g.dx();
  int offset[dim] = {};
  BlockKey last_block = ~BlockKey{0};
  Index first_node = -1;  // storage index of node 0 of last_block
  while (true) {
    double w = 1.0;
    Vec<dim> grad = Vec<dim>::Constant(inv_dx);
    IVec<dim> node;
    for (int a = 0; a < dim; ++a) {
      const int i = offset[a];
      node[a] = axis[a].base + i;
      w *= axis[a].w[i];
      for (int b = 0; b < dim; ++b) grad[b] *= b == a ? axis[a].dw[i] : axis[a].w[i];
    }
    if (w != 0.0 || grad.squaredNorm() != 0.0) {
      // Consecutive stencil nodes mostly share a block: one table lookup per block.
      if (const BlockKey block = g.block_id(node); block != last_block) {
        last_block = block;
        const int slot = g.slot(block);
        first_node = slot < 0 ? -1 : static_cast<Index>(slot) * SparseGrid<dim>::nodes_per_block;
      }
      MPM_VERIFY(first_node >= 0, Error, "adaptive grid: a stencil reaches a block that prepare() did not allocate");
      const Index k = first_node + SparseGrid<dim>::local_index(node);
      fn(k, w, grad, Vec<dim>(g.origin() + g.dx() * node.template cast<double>()));
    }
    int a = 0;
    for (; a < dim; ++a) {
      if (++offset[a] < axis[a].count) break;
      offset[a] = 0;
    }
    if (a == dim) return;
  }
}

template <int dim>
template <class Fn>
void AdaptiveGrid<dim>::for_each_push_target(Fn&& fn) const {
  for (int m = 0; m < levels(); ++m) {
    const PushTable& t = push_tables_[m];
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, t.target.size(), 256), [&](const auto& range) {
      for (std::size_t s = range.begin(); s != range.end(); ++s)
        fn(m, static_cast<std::size_t>(t.target[s]), t.source.data() + t.begin[s], t.source.data() + t.begin[s + 1]);
    });
  }
}

template <int dim>
template <class T>
void AdaptiveGrid<dim>::clear_ghosts(const std::vector<std::vector<T>*>& channel) const {
  for (int n = 0; n < levels(); ++n) {
    const Ghosts& g = ghosts_[n];
    std::vector<T>& values = *channel[n];
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, g.node.size(), 4096), [&](const auto& range) {
      for (std::size_t j = range.begin(); j != range.end(); ++j) {
        T& value = values[static_cast<std::size_t>(g.node[j])];
        value = T(0 * value);
      }
    });
  }
}

template <int dim>
template <class T>
void AdaptiveGrid<dim>::push(std::vector<std::vector<T>*> channel) const {
  for_each_push_target([&](int m, std::size_t i, const PushSource* first, const PushSource* last) {
    T& target = (*channel[m])[i];
    for (const PushSource* s = first; s != last; ++s) {
      const Ghosts& g = ghosts_[s->level];
      target += g.link[s->link].weight * (*channel[s->level])[static_cast<std::size_t>(g.node[s->ghost])];
    }
  });
  clear_ghosts(channel);
}

}  // namespace mpm::adaptive
