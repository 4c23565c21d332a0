#include <mpm/adaptive/adaptive_grid.h>
#include <mpm/adaptive/constrained_basis.h>
#include <mpm/core/error.h>
#include <mpm/core/kernels.h>

#include "lattice_keys.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <iterator>
#include <sstream>
#include <tuple>

#include <tbb/parallel_for.h>

namespace mpm::adaptive {

namespace {
const Eigen::IOFormat kList(Eigen::FullPrecision, Eigen::DontAlignCols, ", ", ", ");

// Room for `extra` more elements in v, the capacity grown by at least a quarter when it runs out.
template <class T>
void reserve_more(std::vector<T>& v, std::size_t extra) {
  if (v.size() + extra > v.capacity()) v.reserve(v.size() + std::max(extra, v.size() / 4));
}

// A bucket's patch (its block and the +1 neighbours: 2B nodes per axis) in two layouts of one
// set of nodes: rows of 2B node bits along axis 0 (row r = i_1 + 2B i_2), and the 64-bit node
// masks of its 2^dim blocks (bit local_index, block `corner`: bit a set for the upper half on
// axis a). The rows are where stencils are marked and read; the masks are the grid's.
template <int dim>
using PatchRows = std::array<std::uint32_t, ipow(2 * SparseGrid<dim>::block_size, dim - 1)>;
template <int dim>
using PatchBlocks = std::array<std::uint64_t, 1 << dim>;
// Row r's two blocks (corner and corner | 1, axis 0 below and above) and its first node's bit.
template <int dim>
void place_patch_row(int r, int& corner, int& shift) {
  constexpr int B = SparseGrid<dim>::block_size, W = 2 * B;
  corner = shift = 0;
  for (int a = 1, rest = r; a < dim; ++a, rest /= W) {
    corner |= (rest % W >= B) << a;
    shift |= (rest % W & (B - 1)) << (a * SparseGrid<dim>::block_bits);
  }
}
template <int dim>
PatchRows<dim> rows_of_blocks(const PatchBlocks<dim>& block) {
  constexpr int B = SparseGrid<dim>::block_size;
  constexpr std::uint64_t block_row = (std::uint64_t{1} << B) - 1;
  static_assert(2 * B <= 32);
  PatchRows<dim> row;
  for (int r = 0; r < static_cast<int>(row.size()); ++r) {
    int corner, shift;
    place_patch_row<dim>(r, corner, shift);
    row[static_cast<std::size_t>(r)] = static_cast<std::uint32_t>((block[corner] >> shift & block_row) |
                                                                  (block[corner | 1] >> shift & block_row) << B);
  }
  return row;
}
template <int dim>
PatchBlocks<dim> blocks_of_rows(const PatchRows<dim>& row) {
  constexpr int B = SparseGrid<dim>::block_size;
  constexpr std::uint64_t block_row = (std::uint64_t{1} << B) - 1;
  PatchBlocks<dim> block{};
  for (int r = 0; r < static_cast<int>(row.size()); ++r) {
    int corner, shift;
    place_patch_row<dim>(r, corner, shift);
    block[corner] |= (row[static_cast<std::size_t>(r)] & block_row) << shift;
    block[corner | 1] |= (row[static_cast<std::size_t>(r)] >> B & block_row) << shift;
  }
  return block;
}

// A node's coordinates within its block packed into one byte (block_bits per axis), and back:
// prepare() finds each regular particle's stencil base once and its later passes read the byte.
template <int dim>
std::uint8_t pack_in_block(const IVec<dim>& node) {
  static_assert(dim * SparseGrid<dim>::block_bits <= 8);
  int packed = 0;
  for (int a = dim - 1; a >= 0; --a)
    packed = packed << SparseGrid<dim>::block_bits | (node[a] & (SparseGrid<dim>::block_size - 1));
  return static_cast<std::uint8_t>(packed);
}
template <int dim>
IVec<dim> unpack_in_block(std::uint8_t packed) {
  IVec<dim> local;
  for (int a = 0; a < dim; ++a, packed >>= SparseGrid<dim>::block_bits)
    local[a] = packed & (SparseGrid<dim>::block_size - 1);
  return local;
}

// Splits 0 .. n-1 by class (class_of(i) in [0, classes)) into one list per class, each in
// ascending order, in parallel: every chunk counts its members per class, then writes them
// after the earlier chunks' (the result does not depend on the thread count).
template <class ClassOf>
std::vector<std::vector<std::uint32_t>> split_by_class(std::size_t n, int classes, ClassOf&& class_of) {
  constexpr std::size_t chunk = 1 << 14;
  const std::size_t chunks = (n + chunk - 1) / chunk;
  std::vector<std::uint32_t> place(chunks * static_cast<std::size_t>(classes), 0);  // chunk-major
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
    for (std::size_t i = c * chunk; i < std::min(n, (c + 1) * chunk); ++i) ++place[c * classes + class_of(i)];
  });
  std::vector<std::vector<std::uint32_t>> out(static_cast<std::size_t>(classes));
  for (int q = 0; q < classes; ++q) {
    std::uint32_t next = 0;
    for (std::size_t c = 0; c < chunks; ++c) {
      const std::uint32_t count = place[c * classes + q];
      place[c * classes + q] = next;
      next += count;
    }
    out[q].resize(next);
  }
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
    for (std::size_t i = c * chunk; i < std::min(n, (c + 1) * chunk); ++i) {
      const int q = class_of(i);
      out[q][place[c * classes + q]++] = static_cast<std::uint32_t>(i);
    }
  });
  return out;
}

// The colour of a block (parity of its coordinates): buckets of one colour share no node.
template <int dim>
int block_color(const IVec<dim>& block_coord) {
  int color = 0;
  for (int a = 0; a < dim; ++a) color |= (block_coord[a] & 1) << a;
  return color;
}
}  // namespace

void GimpAxis::compute(double xi, double h) {
  if (h == 0.5) {  // the quadratic B-spline, the common case: a particle on its own level
    QuadraticBSpline{}(xi, base, w, dw);
    count = QuadraticBSpline::support;
    return;
  }
  base = static_cast<int>(std::floor(xi - h - 1.0)) + 1;             // first node with |xi - j| < 1 + h
  count = static_cast<int>(std::ceil(xi + h + 1.0)) - 1 - base + 1;  // through the last one
  const double inv = 0.5 / h;
  for (int k = 0; k < count; ++k) {
    const double r = xi - (base + k);
    w[k] = (UGimp::hat_integral(r + h) - UGimp::hat_integral(r - h)) * inv;
    dw[k] = (UGimp::hat(r + h) - UGimp::hat(r - h)) * inv;
  }
}

template <int dim>
AdaptiveGrid<dim>::AdaptiveGrid(CellTree<dim> tree, int points_per_axis)
    : tree_(std::move(tree)), points_per_axis_(points_per_axis) {
  MPM_VERIFY(points_per_axis >= 1, InputError, "adaptive grid: at least one particle per axis per cell");
  const Vec<dim> hi = tree_.origin() + tree_.dx(0) * tree_.base_cells().template cast<double>();
  for (int n = 0; n < tree_.levels(); ++n) levels_.emplace_back(tree_.origin(), hi, tree_.dx(n));
  for (int t = 0; t < tree_.levels(); ++t)
    for (int n = 0; n < tree_.levels(); ++n) half_cells_[t * max_levels + n] = 0.5 * particle_size(t) / levels_[n].dx();
  ghosts_.resize(tree_.levels());
  regular_.resize(static_cast<std::size_t>(regular_groups()));
  near_embedded_.resize(static_cast<std::size_t>(regular_groups()));
  near_masks_.resize(static_cast<std::size_t>(regular_groups()));
}

template <int dim>
bool AdaptiveGrid<dim>::prepare(const std::vector<Vec<dim>>& x, const std::vector<std::uint16_t>& type,
                                const std::string& stage, const MoveParticles& move) {
  MPM_VERIFY(x.size() == type.size(), InputError, "adaptive grid: one particle type per particle");
  // The node statuses pack lattice points in StatusLink::point_bits per axis: CellTree refuses a
  // finest level of 2^20 or more cells per axis.
  MPM_ASSERT(((tree_.base_cells() * tree_.scale(0)).array() < (1 << StatusLink::point_bits)).all());
  const int L = levels();
  constexpr int B = SparseGrid<dim>::block_size;
  class_ = std::vector<ParticleClass>(x.size());  // (resampling changes the count: no spare capacity held)
  std::vector<std::vector<BlockKey>> own_blocks(L);
  // The irregular particles by (transfer level, block of the first stencil node), and the
  // most blocks a stencil spans on an axis: the colouring's period.
  std::vector<std::tuple<int, BlockKey, std::uint32_t>> irregular_at;
  int span = 1;

  // Transfer level, half-size and, for a particle of a regular group (on its own level, or with
  // a box of one cell of its level) whose stencil lies inside the level, its bucket's block, in
  // parallel (the tree walk is the cost). Those (regular) go in buckets for the uniform loops;
  // the loop after it reports the first bad particle and takes the others (irregular) through
  // their general stencil.
  const int G = regular_groups();
  std::vector<std::uint8_t> group(x.size(), static_cast<std::uint8_t>(G)), base_in_block(x.size());
  std::vector<BlockKey> bucket(x.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 4096), [&](const auto& range) {
    CellId<dim> leaf;  // the last particle's leaf
    for (std::size_t p = range.begin(); p != range.end(); ++p) {
      class_[p].level = -1;  // reported below (a type out of range first)
      if (type[p] >= L || !x[p].allFinite()) continue;
      class_[p].type = static_cast<std::int8_t>(type[p]);
      const double half = 0.5 * particle_size(type[p]);
      const int n = tree_.finest_level_in(x[p].array() - half, x[p].array() + half, leaf);
      class_[p].level = static_cast<std::int8_t>(n);
      if (n < 0) continue;
      const SparseGrid<dim>& g = levels_[n];
      // On its own level, regular_kernel()'s stencil holds the general one; with a box of one
      // cell, the general weights are the quadratic B-spline's.
      if (n == type[p] || type[p] == cell_box_type(n)) {
        const IVec<dim> base = uniform_base(n, x[p]);
        if ((base.array() >= 0).all() && (base.array() + 2 < g.node_counts().array()).all()) {
          bucket[p] = g.block_id(base);
          base_in_block[p] = pack_in_block<dim>(base);
          group[p] = static_cast<std::uint8_t>(groups_per_level * n + (n != type[p]));
        }
      }
    }
  });
  std::vector<std::vector<std::uint32_t>> by_group =
      split_by_class(x.size(), G + 1, [&](std::size_t p) { return group[p]; });
  for (const std::uint32_t p : by_group[G]) {
    MPM_VERIFY(type[p] < L, InputError,
               "stage '" + stage + "': particle " + std::to_string(p) + " has type " + std::to_string(type[p]) +
                   ", outside the grid's levels [0, " + std::to_string(L - 1) + "]");
    const int n = class_[p].level;
    if (n < 0) {
      std::ostringstream s;
      s.precision(9);
      s << "stage '" << stage << "': particle " << p << (x[p].allFinite() ? " at (" : " has a non-finite position (")
        << x[p].transpose().format(kList) << ")"
        << (x[p].allFinite() ? " left the grid domain; keep particles inside the walls" : "");
      throw NumericalError(s.str());
    }
    const SparseGrid<dim>& g = levels_[n];
    const double h = half_cells(p);
    IVec<dim> first, last;
    GimpAxis axis[dim];
    axis_weights(n, h, x[p], axis);
    for (int a = 0; a < dim; ++a) {
      first[a] = axis[a].base;
      last[a] = axis[a].base + axis[a].count - 1;
      if (first[a] < 0 || last[a] >= g.node_counts()[a]) {
        std::ostringstream s;
        s.precision(9);
        s << "stage '" << stage << "': the stencil of particle " << p << " at (" << x[p].transpose().format(kList)
          << ") leaves the grid (axis " << a << "); keep particles inside the walls";
        throw NumericalError(s.str());
      }
      first[a] /= B;
      last[a] /= B;
    }
    irregular_at.emplace_back(n, g.block_id(first * B), static_cast<std::uint32_t>(p));
    span = std::max(span, (last - first).maxCoeff() + 1);
    IVec<dim> b = first;
    while (true) {
      const BlockKey key = g.block_id(b * B);
      if (own_blocks[n].empty() || own_blocks[n].back() != key) own_blocks[n].push_back(key);
      int a = 0;
      for (; a < dim; ++a) {
        if (++b[a] <= last[a]) break;
        b[a] = first[a];
      }
      if (a == dim) break;
    }
  }
  // The regular particles of each group in buckets: a stable sort by block, in parallel. A
  // bucket's patch covers its block and the +1 neighbours on every axis.
  std::vector<std::vector<BlockKey>> blocks(L);
  for (int grp = 0; grp < G; ++grp) {
    const int n = group_level(grp);
    const std::vector<std::uint32_t>& members = by_group[grp];
    std::vector<BlockKey> keys(members.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, members.size(), 1 << 14), [&](const auto& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) keys[i] = bucket[members[i]];
    });
    KeyOrder sorted = sort_keys(keys);
    ParticleBuckets<dim>& b = regular_[grp];
    b = ParticleBuckets<dim>{};
    if (sorted.identity) {
      b.particle = members;
    } else {
      b.particle.resize(members.size());
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, members.size(), 1 << 14), [&](const auto& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) b.particle[i] = members[sorted.order[i]];
      });
    }
    b.begin = std::move(sorted.begin);
    b.block = std::move(sorted.key);
    for (int k = 0; k < b.count(); ++k) {
      const IVec<dim> c = levels_[n].block_coord(b.block[k]);
      b.by_color[block_color<dim>(c)].push_back(k);
      for (int corner = 0; corner < (1 << dim); ++corner) {
        IVec<dim> nb = c;
        for (int a = 0; a < dim; ++a) nb[a] += (corner >> a) & 1;
        own_blocks[n].push_back(levels_[n].block_id(nb * B));
      }
    }
  }

  // The nodes the stencils reach, per block of each level's stencil blocks.
  group_irregular(irregular_at, span);
  std::vector<std::vector<std::uint64_t>> reached_nodes(L);
  for (int n = 0; n < L; ++n) {
    std::vector<BlockKey>& own = own_blocks[n];
    sort_unique_points<dim>(own, SparseGrid<dim>::key_bits);
    reached_nodes[n] = stencil_nodes(n, x, base_in_block, own);
  }

  // Status of the nodes reached: real on its level, or a ghost with links given by lattice
  // point and home level until the grids are allocated. A ghost that is not simply a real node
  // of another level (one link of weight 1) is an embedded ghost: its bit is set in its block's
  // mask. The statuses depend on the tree only: they are kept per block while the tree stays
  // the same (a static refinement: always), and computed for the nodes a block does not know.
  const bool same_tree = tree_ == status_tree_;
  if (!same_tree || statuses_stale_) forget_changed_statuses();
  for (int n = 0; n < L; ++n) {
    const std::vector<BlockKey>& own = own_blocks[n];
    LevelStatus& status = status_[n];
    // The blocks with a node newly reached, computed anew in parallel for every node they know
    // or now reach (the embedding walks are the cost), appended in block order.
    std::vector<std::size_t> fresh;
    std::vector<int> fresh_entry;  // the block's entry in status.blocks, -1 for a new block
    std::vector<std::uint64_t> fresh_nodes;
    for (std::size_t b = 0; b < own.size(); ++b) {
      const int m = status.index.find(own[b]);
      const std::uint64_t known = m < 0 ? 0 : status.blocks[static_cast<std::size_t>(m)].known;
      if (m < 0 || (reached_nodes[n][b] & ~known) != 0) {
        fresh.push_back(b);
        fresh_entry.push_back(m);
        fresh_nodes.push_back(known | reached_nodes[n][b]);
      }
    }
    std::vector<FreshStatus> computed(fresh.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, fresh.size(), 4), [&](const auto& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i)
        computed[i] = block_status(n, own[fresh[i]], fresh_nodes[i]);
    });
    // The statuses stay between steps and their capacity is memory held: grown by a quarter
    // when full, not doubled as by the appends.
    std::size_t more_ghosts = 0, more_links = 0, more_reached = 0;
    for (const FreshStatus& c : computed) {
      more_ghosts += c.ghosts.size();
      more_links += c.links.size();
      more_reached += c.reached.size();
    }
    reserve_more(status.ghosts, more_ghosts);
    reserve_more(status.links, more_links);
    reserve_more(status.reached, more_reached);
    reserve_more(status.blocks, fresh.size());
    for (std::size_t i = 0; i < fresh.size(); ++i) {
      FreshStatus& c = computed[i];
      const auto link_offset = static_cast<std::uint32_t>(status.links.size());
      BlockStatus block{static_cast<std::uint32_t>(status.ghosts.size()),  0, c.embedded,   fresh_nodes[i],
                        static_cast<std::uint32_t>(status.reached.size()), 0, c.depends_lo, c.depends_hi};
      for (PendingGhost& ghost : c.ghosts) {
        ghost.first_link += link_offset;
        ghost.end_link += link_offset;
      }
      status.ghosts.insert(status.ghosts.end(), c.ghosts.begin(), c.ghosts.end());
      std::transform(c.links.begin(), c.links.end(), std::back_inserter(status.links), &StatusLink::pack);
      status.reached.insert(status.reached.end(), c.reached.begin(), c.reached.end());
      block.end_ghost = static_cast<std::uint32_t>(status.ghosts.size());
      block.end_reached = static_cast<std::uint32_t>(status.reached.size());
      if (const int m = fresh_entry[i]; m >= 0) {  // the old entries stay unused
        BlockStatus& old = status.blocks[static_cast<std::size_t>(m)];
        status.unused += old.end_ghost - old.first_ghost;
        old = block;
      } else {
        status.index.insert(own[fresh[i]], static_cast<int>(status.blocks.size()));
        status.blocks.push_back(block);
      }
    }
    // Unused entries (replaced, or of blocks no longer reached) are dropped at the next call
    // once they are as many as the used ones.
    statuses_stale_ =
        statuses_stale_ || 2 * status.unused > status.ghosts.size() || status.blocks.size() > 2 * own.size();
    blocks[n].insert(blocks[n].end(), own.begin(), own.end());
    for (BlockKey key : own) {
      const BlockStatus& block = status.blocks[static_cast<std::size_t>(status.index.find(key))];
      for (std::uint32_t r = block.first_reached; r < block.end_reached; ++r)
        blocks[status.reached[r].first].push_back(status.reached[r].second);
    }
  }

  // The bucketed particles whose stencil holds an embedded ghost are also listed: APIC adds
  // the ghosts' affine terms for them (adaptive_transfer.cpp).
  for (int grp = 0; grp < G; ++grp) {
    const int n = group_level(grp);
    const SparseGrid<dim>& g = levels_[n];
    const LevelStatus& status = status_[n];
    auto embedded_mask = [&](const IVec<dim>& block_coord) -> std::uint64_t {
      const int m = status.index.find(g.block_id(block_coord * B));
      return m >= 0 ? status.blocks[static_cast<std::size_t>(m)].embedded : 0;
    };
    // Whether each bucketed particle's 3^dim stencil holds an embedded ghost, in parallel by
    // bucket, and how many per bucket: per bucket, the embedded bits of its patch as rows; per
    // particle, the three bits of each of its stencil's rows shifted out of them.
    constexpr int W = 2 * B;
    const ParticleBuckets<dim>& reg = regular_[grp];
    std::vector<std::uint32_t> near(reg.particle.size(), 0);  // the stencil's embedded ghosts, by bit
    std::vector<std::uint32_t> near_count(static_cast<std::size_t>(reg.count()), 0);
    tbb::parallel_for(tbb::blocked_range<int>(0, reg.count(), 8), [&](const auto& range) {
      for (int k = range.begin(); k != range.end(); ++k) {
        const IVec<dim> c = g.block_coord(reg.block[k]);
        PatchBlocks<dim> patch_mask;  // embedded masks of the patch's blocks
        bool check_nodes = false;
        for (int corner = 0; corner < (1 << dim); ++corner) {
          IVec<dim> nb = c;
          for (int a = 0; a < dim; ++a) nb[a] += (corner >> a) & 1;
          patch_mask[corner] = embedded_mask(nb);
          check_nodes = check_nodes || patch_mask[corner] != 0;
        }
        if (!check_nodes) continue;
        const PatchRows<dim> row = rows_of_blocks<dim>(patch_mask);
        for (std::uint32_t i = reg.begin[k]; i < reg.begin[k + 1]; ++i) {
          const IVec<dim> base = unpack_in_block<dim>(base_in_block[reg.particle[i]]);
          std::uint32_t bits = 0;
          for (int j = 0; j < ipow(3, dim); j += 3) {  // a row of three nodes along axis 0
            int r = 0;
            for (int a = dim - 1; a >= 1; --a) r = r * W + base[a] + stencil_offsets[j][a];
            bits |= static_cast<std::uint32_t>(row[static_cast<std::size_t>(r)] >> base[0] & 7) << j;
          }
          near[i] = bits;
          near_count[static_cast<std::size_t>(k)] += bits != 0;
        }
      }
    });
    // The near ones in buckets of their own: the buckets that hold any, then their particles
    // and masks filled per bucket in parallel.
    ParticleBuckets<dim>& ne = near_embedded_[grp];
    ne = ParticleBuckets<dim>{};
    std::vector<int> near_bucket;  // bucket of reg behind each bucket of ne
    std::uint32_t near_total = 0;
    for (int k = 0; k < reg.count(); ++k) {
      if (near_count[static_cast<std::size_t>(k)] == 0) continue;
      ne.by_color[block_color<dim>(g.block_coord(reg.block[k]))].push_back(ne.count());
      ne.begin.push_back(near_total);
      ne.block.push_back(reg.block[k]);
      near_bucket.push_back(k);
      near_total += near_count[static_cast<std::size_t>(k)];
    }
    ne.begin.push_back(near_total);
    ne.particle.resize(near_total);
    near_masks_[grp] = std::vector<std::uint32_t>(near_total);  // not the capacity of a larger step's
    tbb::parallel_for(tbb::blocked_range<int>(0, ne.count(), 16), [&](const auto& range) {
      for (int e = range.begin(); e != range.end(); ++e) {
        const int k = near_bucket[static_cast<std::size_t>(e)];
        std::uint32_t out = ne.begin[e];
        for (std::uint32_t i = reg.begin[k]; i < reg.begin[k + 1]; ++i)
          if (near[i]) {
            ne.particle[out] = reg.particle[i];
            near_masks_[grp][out++] = near[i];
          }
      }
    });
  }
  const bool moved = move && store_in_transfer_order(move);

  // The grids follow from the tree and the blocks alone, the ghost tables also from the nodes
  // the stencils reach: while neither the tree nor the blocks change (most steps: particles
  // seldom cross into new blocks), the grids stand, and so do the tables while they hold every
  // node reached.
  bool same_blocks = same_tree && own_blocks == own_blocks_;
  for (int n = 0; n < L; ++n) {
    sort_unique_points<dim>(blocks[n], SparseGrid<dim>::key_bits);
    same_blocks = same_blocks && blocks[n] == levels_[n].active_blocks();
  }
  if (same_blocks) {
    bool tables_hold = true;
    for (int n = 0; n < L; ++n)
      for (std::size_t b = 0; b < reached_nodes[n].size(); ++b)
        tables_hold = tables_hold && (reached_nodes[n][b] & ~tabled_[n][b]) == 0;
    if (tables_hold) return moved;
  } else {
    own_blocks_ = own_blocks;
    for (int n = 0; n < L; ++n) levels_[n].activate(blocks[n]);
  }
  tabled_ = std::move(reached_nodes);

  // Ghost tables in storage indices for the nodes the stencils reach, each block's ghosts
  // filled in parallel at offsets counted first (their order: the blocks', then the
  // statuses').
  for (int n = 0; n < L; ++n) {
    Ghosts& g = ghosts_[n];
    g = Ghosts{};
    MPM_VERIFY(levels_[n].node_storage() <= std::numeric_limits<std::uint32_t>::max(), Error,
               "adaptive grid: level " + std::to_string(n) + " holds more nodes than 32-bit ghost links address");
    const std::size_t storage_blocks = levels_[n].node_storage() / SparseGrid<dim>::nodes_per_block;
    g.block_mask.assign(storage_blocks, 0);
    g.block_first.assign(storage_blocks, 0);
    const LevelStatus& status = status_[n];
    const std::vector<BlockKey>& own = own_blocks[n];
    const auto tabled = [&](std::size_t b, const PendingGhost& ghost) {
      return (tabled_[n][b] >> SparseGrid<dim>::local_index(ghost.node) & 1) != 0;
    };
    std::vector<const BlockStatus*> block(own.size());
    std::vector<std::uint32_t> first_ghost(own.size() + 1, 0);
    for (std::size_t b = 0; b < own.size(); ++b) {
      block[b] = &status.blocks[static_cast<std::size_t>(status.index.find(own[b]))];
      first_ghost[b + 1] = first_ghost[b];
      for (std::uint32_t j = block[b]->first_ghost; j < block[b]->end_ghost; ++j)
        first_ghost[b + 1] += tabled(b, status.ghosts[j]);
    }
    const std::size_t ghosts = first_ghost.back();
    g.node.resize(ghosts);
    g.begin.resize(ghosts + 1);
    g.moment.resize(ghosts);
    int moments = 0;
    for (std::size_t b = 0; b < own.size(); ++b)
      for (std::uint32_t j = block[b]->first_ghost, out = first_ghost[b]; j < block[b]->end_ghost; ++j) {
        const PendingGhost& ghost = status.ghosts[j];
        if (!tabled(b, ghost)) continue;
        g.begin[out + 1] = g.begin[out] + (ghost.end_link - ghost.first_link);
        g.moment[out] = (block[b]->embedded >> SparseGrid<dim>::local_index(ghost.node) & 1) != 0 ? moments++ : -1;
        ++out;
      }
    g.spread.resize(static_cast<std::size_t>(moments));
    g.link.resize(g.begin.back());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, own.size(), 8), [&](const auto& range) {
      for (std::size_t b = range.begin(); b != range.end(); ++b) {
        for (std::uint32_t j = block[b]->first_ghost, out = first_ghost[b]; j < block[b]->end_ghost; ++j) {
          const PendingGhost& ghost = status.ghosts[j];
          if (!tabled(b, ghost)) continue;
          const Index k = levels_[n].node_index(ghost.node);
          const Vec<dim> xk = node_position(n, k);
          std::array<double, dim*(dim + 1) / 2> spread{};
          std::uint32_t l_out = g.begin[out];
          for (std::size_t l = ghost.first_link; l < ghost.end_link; ++l, ++l_out) {
            const NodeWeight<dim> link = status.links[l].unpack();
            g.link[l_out] = {
                static_cast<std::uint32_t>(levels_[link.level].node_index(link.point / tree_.scale(link.level))),
                link.level, link.weight};
            const Vec<dim> r = link_offset(g.link[l_out], xk);
            for (int a = 0, e = 0; a < dim; ++a)
              for (int c = a; c < dim; ++c, ++e) spread[e] += link.weight * r[a] * r[c];
          }
          // One block's ghosts in node order (the statuses': block_status()), so of_node()
          // counts them.
          const auto slot = static_cast<std::size_t>(k / SparseGrid<dim>::nodes_per_block);
          const std::uint64_t bit = std::uint64_t{1} << (k % SparseGrid<dim>::nodes_per_block);
          if (g.block_mask[slot] == 0) g.block_first[slot] = static_cast<std::uint32_t>(out);
          MPM_ASSERT(g.block_mask[slot] < bit && g.block_first[slot] + std::popcount(g.block_mask[slot]) == out);
          g.block_mask[slot] |= bit;
          g.node[out] = k;
          if (const int m = g.moment[out]; m >= 0) g.spread[static_cast<std::size_t>(m)] = spread;
          ++out;
        }
      }
    });
  }
  build_push_tables();
  return moved;
}

template <int dim>
void AdaptiveGrid<dim>::group_irregular(std::vector<std::tuple<int, BlockKey, std::uint32_t>>& at, int span) {
  std::sort(at.begin(), at.end());
  irregular_.clear();
  IrregularGroups& groups = irregular_groups_;
  groups.begin.assign(1, 0);
  groups.by_color.assign(static_cast<std::size_t>(ipow(span, dim)), {});
  for (std::size_t i = 0; i < at.size(); ++i) {
    const auto& [n, block, p] = at[i];
    if (i == 0 || n != std::get<0>(at[i - 1]) || block != std::get<1>(at[i - 1])) {
      if (i > 0) groups.begin.push_back(static_cast<std::uint32_t>(i));
      // Groups of one colour lie `span` blocks apart on some axis: their stencils share no node.
      const IVec<dim> c = levels_[n].block_coord(block);
      int color = 0;
      for (int a = dim - 1; a >= 0; --a) color = color * span + c[a] % span;
      groups.by_color[static_cast<std::size_t>(color)].push_back(static_cast<int>(groups.begin.size()) - 1);
    }
    irregular_.push_back(p);
  }
  if (!at.empty()) groups.begin.push_back(static_cast<std::uint32_t>(at.size()));
}

template <int dim>
bool AdaptiveGrid<dim>::store_in_transfer_order(const MoveParticles& move) {
  std::vector<std::uint32_t> order;
  order.reserve(class_.size());
  for (const ParticleBuckets<dim>& b : regular_) order.insert(order.end(), b.particle.begin(), b.particle.end());
  order.insert(order.end(), irregular_.begin(), irregular_.end());
  MPM_ASSERT(order.size() == class_.size());
  if (!scattered(order)) return false;
  move(order);
  std::vector<std::uint32_t> renamed(order.size());  // old index -> new
  for (std::size_t i = 0; i < order.size(); ++i) renamed[order[i]] = static_cast<std::uint32_t>(i);
  auto reorder = [&](auto& values) {
    auto old = values;
    for (std::size_t i = 0; i < order.size(); ++i) values[i] = old[order[i]];
  };
  reorder(class_);
  std::uint32_t next = 0;
  for (ParticleBuckets<dim>& b : regular_)
    for (std::uint32_t& p : b.particle) p = next++;
  for (std::uint32_t& p : irregular_) p = next++;
  for (ParticleBuckets<dim>& b : near_embedded_)
    for (std::uint32_t& p : b.particle) p = renamed[p];
  return true;
}

template <int dim>
std::vector<std::uint64_t> AdaptiveGrid<dim>::stencil_nodes(int n, const std::vector<Vec<dim>>& x,
                                                            const std::vector<std::uint8_t>& base_in_block,
                                                            const std::vector<BlockKey>& own) const {
  constexpr int B = SparseGrid<dim>::block_size, W = 2 * B;  // a bucket's patch: 2 blocks per axis
  constexpr int rows = ipow(W, dim - 1);                     // its rows of W nodes along axis 0
  static_assert(SparseGrid<dim>::nodes_per_block <= 64 && W <= 32);
  const SparseGrid<dim>& g = levels_[n];
  std::vector<std::uint64_t> reached(own.size(), 0);
  // Buckets of neighbouring blocks reach the same blocks: the bits are or-ed in atomically
  // (the result does not depend on the order).
  const auto add = [&](BlockKey key, std::uint64_t bits) {
    const auto it = std::lower_bound(own.begin(), own.end(), key);
    MPM_ASSERT(it != own.end() && *it == key);
    std::atomic_ref<std::uint64_t>(reached[static_cast<std::size_t>(it - own.begin())])
        .fetch_or(bits, std::memory_order_relaxed);
  };
  // The regular particles' 3^dim stencils, per bucket of the level's groups: the stencils'
  // first nodes marked in the patch's rows, dilated by two nodes along each axis, then cut
  // into the patch's blocks.
  for (int grp = groups_per_level * n; grp < groups_per_level * (n + 1); ++grp) {
    const ParticleBuckets<dim>& reg = regular_[grp];
    tbb::parallel_for(tbb::blocked_range<int>(0, reg.count(), 8), [&](const auto& range) {
      for (int k = range.begin(); k != range.end(); ++k) {
        const IVec<dim> first = g.block_coord(reg.block[k]) * B;
        PatchRows<dim> row{};
        for (std::uint32_t i = reg.begin[k]; i < reg.begin[k + 1]; ++i) {
          const IVec<dim> base = unpack_in_block<dim>(base_in_block[reg.particle[i]]);
          int r = 0;
          for (int a = dim - 1; a >= 1; --a) r = r * W + base[a];
          row[static_cast<std::size_t>(r)] |= 1u << base[0];
        }
        for (std::uint32_t& r : row) r |= r << 1 | r << 2;
        for (int a = 1, stride = 1; a < dim; ++a, stride *= W)
          for (int r = rows - 1; r >= 0; --r) {  // from the top: the rows below are not yet dilated
            const int c = r / stride % W;
            if (c >= 1) row[static_cast<std::size_t>(r)] |= row[static_cast<std::size_t>(r - stride)];
            if (c >= 2) row[static_cast<std::size_t>(r)] |= row[static_cast<std::size_t>(r - 2 * stride)];
          }
        const PatchBlocks<dim> bits = blocks_of_rows<dim>(row);
        for (int corner = 0; corner < (1 << dim); ++corner) {
          IVec<dim> block = first / B;
          for (int a = 0; a < dim; ++a) block[a] += (corner >> a) & 1;
          if (bits[corner]) add(g.block_id(block * B), bits[corner]);
        }
      }
    });
  }
  // The irregular particles' general stencils, node by node.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, irregular_.size(), 64), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const std::uint32_t p = irregular_[i];
      if (class_[p].level != n) continue;
      GimpAxis axis[dim];
      axis_weights(n, half_cells(p), x[p], axis);
      IVec<dim> first, last;
      for (int a = 0; a < dim; ++a) {
        first[a] = axis[a].base;
        last[a] = axis[a].base + axis[a].count - 1;
      }
      BlockKey block = ~BlockKey{0};  // consecutive nodes mostly share a block: one add per run
      std::uint64_t bits = 0;
      for_each_in_box<dim>(first, last, [&](const IVec<dim>& node) {
        if (const BlockKey key = g.block_id(node); key != block) {
          if (bits) add(block, bits);
          block = key;
          bits = 0;
        }
        bits |= std::uint64_t{1} << SparseGrid<dim>::local_index(node);
      });
      add(block, bits);
    }
  });
  return reached;
}

template <int dim>
typename AdaptiveGrid<dim>::StatusLink AdaptiveGrid<dim>::StatusLink::pack(const NodeWeight<dim>& link) {
  std::uint64_t key = 0;
  for (int a = 0; a < dim; ++a) {
    MPM_ASSERT(link.point[a] >= 0 && link.point[a] < std::int64_t{1} << point_bits);  // prepare() checks the domain
    key = key << point_bits | static_cast<std::uint64_t>(link.point[a]);
  }
  return {key << level_bits | static_cast<std::uint64_t>(link.level), link.weight};
}

template <int dim>
NodeWeight<dim> AdaptiveGrid<dim>::StatusLink::unpack() const {
  NodeWeight<dim> link;
  link.level = static_cast<int>(key & ((1u << level_bits) - 1));
  for (int a = 0; a < dim; ++a)
    link.point[a] =
        static_cast<int>(key >> (level_bits + (dim - 1 - a) * point_bits) & ((std::uint64_t{1} << point_bits) - 1));
  link.weight = weight;
  return link;
}

template <int dim>
typename AdaptiveGrid<dim>::FreshStatus AdaptiveGrid<dim>::block_status(int n, BlockKey key,
                                                                        std::uint64_t nodes) const {
  constexpr int B = SparseGrid<dim>::block_size;
  const SparseGrid<dim>& g = levels_[n];
  const int s = tree_.scale(n);
  FreshStatus out;
  const IVec<dim> origin = g.block_coord(key) * B;
  for (; nodes != 0; nodes &= nodes - 1) {
    const int local = std::countr_zero(nodes);
    IVec<dim> node;
    for (int a = 0; a < dim; ++a) node[a] = origin[a] + ((local >> (a * SparseGrid<dim>::block_bits)) & (B - 1));
    if ((node.array() >= g.node_counts().array()).any()) continue;  // padding beyond the domain
    const IVec<dim> point = node * s;
    out.depends_lo = out.depends_lo.cwiseMin(point);
    out.depends_hi = out.depends_hi.cwiseMax(point);
    if (home_level(tree_, point) == n) continue;  // a real node of this level
    const std::size_t first_link = out.links.size();
    embed(tree_, point, 1.0, out.links);
    out.ghosts.push_back({node, static_cast<std::uint32_t>(first_link), static_cast<std::uint32_t>(out.links.size())});
    if (out.links.size() - first_link > 1 || out.links[first_link].point != point)
      out.embedded |= std::uint64_t{1} << SparseGrid<dim>::local_index(node);
  }
  // The blocks of the real nodes its ghosts reach, once each. An embedding walks through points
  // inside the box of its links (each point lies in the box of the corners it is interpolated
  // from), so the links close the box the statuses depend on.
  for (const NodeWeight<dim>& link : out.links) {
    out.reached.push_back({link.level, levels_[link.level].block_id(link.point / tree_.scale(link.level))});
    out.depends_lo = out.depends_lo.cwiseMin(link.point);
    out.depends_hi = out.depends_hi.cwiseMax(link.point);
  }
  std::sort(out.reached.begin(), out.reached.end());
  out.reached.erase(std::unique(out.reached.begin(), out.reached.end()), out.reached.end());
  return out;
}

template <int dim>
void AdaptiveGrid<dim>::forget_changed_statuses() {
  statuses_stale_ = false;
  const int L = levels();
  if (static_cast<int>(status_.size()) != L || !status_tree_.same_domain(tree_)) {
    status_tree_ = tree_;
    status_.assign(L, LevelStatus{});
    return;
  }
  // A node's status is read off the leaves whose closure holds a point of its embedding (the
  // node, then the corners it is interpolated from, recursively: constrained_basis.cpp). A
  // refinement change alters the leaves in the closure of the changed cell only, so a block's
  // statuses stand unless some changed cell's closure meets the box of its points
  // (BlockStatus::depends_lo/hi); only the last step's blocks are kept. The changed cells are
  // binned by level-0 cell (no cell is larger, so each meets at most 2^dim bins): a block tests
  // the cells of the bins its box meets, not every changed cell.
  const int bin = tree_.scale(0);  // lattice units per bin: a bin is a level-0 cell
  std::vector<std::pair<IVec<dim>, IVec<dim>>> changed;
  std::vector<std::pair<BlockKey, std::uint32_t>> binned;  // (bin, changed cell), sorted
  for (const CellId<dim>& c : tree_.refined_difference(status_tree_)) {
    const int s = tree_.scale(c.level);
    changed.push_back({c.cell * s, (c.cell + IVec<dim>::Ones()) * s});
    for_each_in_box<dim>(IVec<dim>(changed.back().first / bin), IVec<dim>(changed.back().second / bin),
                         [&](const IVec<dim>& b) {
                           binned.push_back({CellTree<dim>::key(b), static_cast<std::uint32_t>(changed.size() - 1)});
                         });
  }
  std::sort(binned.begin(), binned.end());
  const auto near_change = [&](const BlockStatus& block) {
    bool near = false;
    for_each_in_box<dim>(IVec<dim>(block.depends_lo.cwiseMax(0) / bin), IVec<dim>(block.depends_hi.cwiseMax(0) / bin),
                         [&](const IVec<dim>& b) {
                           const BlockKey key = CellTree<dim>::key(b);
                           auto it = std::lower_bound(binned.begin(), binned.end(), std::pair{key, std::uint32_t{0}});
                           for (; !near && it != binned.end() && it->first == key; ++it) {
                             const auto& [lo, hi] = changed[it->second];
                             near = (block.depends_lo.array() <= hi.array()).all() &&
                                    (block.depends_hi.array() >= lo.array()).all();
                           }
                         });
    return near;
  };
  status_tree_ = tree_;
  for (int n = 0; n < L; ++n) {
    const LevelStatus old = std::move(status_[n]);
    LevelStatus& kept = status_[n] = LevelStatus{};
    if (static_cast<int>(own_blocks_.size()) != L) continue;
    // The kept blocks and their place in the new tables, then their copies, in parallel.
    const std::vector<BlockKey>& last_blocks = own_blocks_[n];
    std::vector<int> from(last_blocks.size(), -1);  // the kept blocks' index in `old`
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, last_blocks.size(), 64), [&](const auto& range) {
      for (std::size_t b = range.begin(); b != range.end(); ++b) {
        const int m = old.index.find(last_blocks[b]);
        if (m >= 0 && !near_change(old.blocks[static_cast<std::size_t>(m)])) from[b] = m;
      }
    });
    // A block's ghosts' links lie together: from its first ghost's first link on.
    const auto first_link_of = [&](const BlockStatus& block) {
      return block.end_ghost > block.first_ghost ? old.ghosts[block.first_ghost].first_link : std::size_t{0};
    };
    const auto link_count = [&](const BlockStatus& block) {
      return block.end_ghost > block.first_ghost ? old.ghosts[block.end_ghost - 1].end_link - first_link_of(block)
                                                 : std::size_t{0};
    };
    std::size_t ghosts = 0, reached = 0;
    std::vector<std::size_t> first_link{0};  // per kept block, in the new tables
    std::vector<int> kept_from;              // per kept block: its index in `old`
    for (std::size_t b = 0; b < last_blocks.size(); ++b) {
      if (from[b] < 0) continue;
      BlockStatus block = old.blocks[static_cast<std::size_t>(from[b])];
      first_link.push_back(first_link.back() + link_count(block));
      const std::uint32_t ghost_count = block.end_ghost - block.first_ghost;
      const std::uint32_t reached_count = block.end_reached - block.first_reached;
      block.first_ghost = static_cast<std::uint32_t>(ghosts);
      block.end_ghost = block.first_ghost + ghost_count;
      block.first_reached = static_cast<std::uint32_t>(reached);
      block.end_reached = block.first_reached + reached_count;
      ghosts += ghost_count;
      reached += reached_count;
      kept.index.insert(last_blocks[b], static_cast<int>(kept.blocks.size()));
      kept.blocks.push_back(block);
      kept_from.push_back(from[b]);
    }
    // Room for the new blocks' statuses appended after these (about as many as are dropped).
    kept.ghosts.reserve(old.ghosts.size());
    kept.links.reserve(old.links.size());
    kept.reached.reserve(old.reached.size());
    kept.ghosts.resize(ghosts);
    kept.links.resize(first_link.back());
    kept.reached.resize(reached);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, kept.blocks.size(), 16), [&](const auto& range) {
      for (std::size_t k = range.begin(); k != range.end(); ++k) {
        const BlockStatus& was = old.blocks[static_cast<std::size_t>(kept_from[k])];
        const BlockStatus& now = kept.blocks[k];
        const std::size_t shift = first_link[k] - first_link_of(was);
        for (std::uint32_t j = was.first_ghost, out = now.first_ghost; j < was.end_ghost; ++j, ++out) {
          const PendingGhost& ghost = old.ghosts[j];
          kept.ghosts[out] = {ghost.node, static_cast<std::uint32_t>(ghost.first_link + shift),
                              static_cast<std::uint32_t>(ghost.end_link + shift)};
        }
        std::copy(old.links.begin() + static_cast<std::ptrdiff_t>(first_link_of(was)),
                  old.links.begin() + static_cast<std::ptrdiff_t>(first_link_of(was) + link_count(was)),
                  kept.links.begin() + static_cast<std::ptrdiff_t>(first_link[k]));
        std::copy(old.reached.begin() + was.first_reached, old.reached.begin() + was.end_reached,
                  kept.reached.begin() + now.first_reached);
      }
    });
  }
}

template <int dim>
void AdaptiveGrid<dim>::build_push_tables() {
  // A counting sort of the links by the storage node they reach (stable: each node's links
  // stay in scatter order), then the nodes that any link reaches.
  const int L = levels();
  std::vector<std::vector<std::uint32_t>> first(L);  // per storage node of level m
  for (int m = 0; m < L; ++m) first[m].assign(levels_[m].node_storage() + 1, 0);
  for (const Ghosts& g : ghosts_)
    for (const GhostLink<dim>& link : g.link) ++first[link.level][static_cast<std::size_t>(link.index) + 1];
  push_tables_.assign(L, PushTable{});
  for (int m = 0; m < L; ++m) {
    std::vector<std::uint32_t>& f = first[m];
    PushTable& t = push_tables_[m];
    t.begin.push_back(0);
    for (std::size_t i = 0; i + 1 < f.size(); ++i) {
      if (f[i + 1] > 0) {
        t.target.push_back(static_cast<Index>(i));
        t.begin.push_back(t.begin.back() + f[i + 1]);
      }
      f[i + 1] += f[i];
    }
    t.source.resize(t.begin.back());
  }
  for (int n = 0; n < L; ++n) {
    const Ghosts& g = ghosts_[n];
    MPM_VERIFY(g.node.size() < std::size_t{1} << 29, Error,
               "adaptive grid: level " + std::to_string(n) + " holds more ghosts than the push tables address (2^29)");
    for (std::uint32_t j = 0; j < g.node.size(); ++j)
      for (std::uint32_t l = g.begin[j]; l < g.begin[j + 1]; ++l) {
        const GhostLink<dim>& link = g.link[l];
        push_tables_[link.level].source[first[link.level][static_cast<std::size_t>(link.index)]++] = {
            static_cast<std::uint32_t>(n), j, l};
      }
  }
}

template <int dim>
void AdaptiveGrid<dim>::push_momentum(const std::vector<std::vector<Mat<dim>>>& affine) {
  for_each_push_target([&](int m, std::size_t i, const PushSource* first, const PushSource* last) {
    SparseGrid<dim>& to = levels_[m];
    for (const PushSource* s = first; s != last; ++s) {
      const Ghosts& g = ghosts_[s->level];
      const SparseGrid<dim>& from = levels_[s->level];
      const std::size_t k = static_cast<std::size_t>(g.node[s->ghost]);
      const GhostLink<dim>& link = g.link[s->link];
      to.mass[i] += link.weight * from.mass[k];
      to.velocity[i] +=
          link.weight * (from.velocity[k] + affine[s->level][s->ghost] * link_offset(link, from.node_position(k)));
    }
  });
  clear_ghosts(per_level(&SparseGrid<dim>::mass));
  clear_ghosts(per_level(&SparseGrid<dim>::velocity));
}

template <int dim>
void AdaptiveGrid<dim>::pull_velocity(bool old) {
  for (int n = 0; n < levels(); ++n) {
    Ghosts& g = ghosts_[n];
    SparseGrid<dim>& to = levels_[n];
    g.velocity_moment.resize(g.spread.size());
    // Ghosts read real nodes only and write their own: in parallel.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, g.node.size(), 512), [&](const auto& range) {
      for (std::size_t j = range.begin(); j != range.end(); ++j) {
        const std::size_t k = static_cast<std::size_t>(g.node[j]);
        const Vec<dim> xk = to.node_position(k);
        Vec<dim> v = Vec<dim>::Zero(), v_old = Vec<dim>::Zero();
        Mat<dim> moment = Mat<dim>::Zero();
        for (std::uint32_t l = g.begin[j]; l < g.begin[j + 1]; ++l) {
          const GhostLink<dim>& link = g.link[l];
          const SparseGrid<dim>& from = levels_[link.level];
          const std::size_t i = static_cast<std::size_t>(link.index);
          v += link.weight * from.velocity[i];
          if (old) v_old += link.weight * from.velocity_old[i];
          moment.noalias() += link.weight * from.velocity[i] * link_offset(link, xk).transpose();
        }
        if (const int m = g.moment[j]; m >= 0) g.velocity_moment[static_cast<std::size_t>(m)] = moment;
        to.velocity[k] = v;
        if (old) to.velocity_old[k] = v_old;
      }
    });
  }
}

template <int dim>
std::size_t AdaptiveGrid<dim>::memory_bytes() const {
  std::size_t bytes = index_bytes();
  for (const SparseGrid<dim>& g : levels_) bytes += g.memory_bytes();
  return bytes;
}

template <int dim>
std::size_t AdaptiveGrid<dim>::index_bytes() const {
  std::size_t bytes = tree_.memory_bytes() + class_.capacity() * sizeof(ParticleClass);
  bytes += irregular_.capacity() * sizeof(std::uint32_t);
  for (const Ghosts& g : ghosts_)
    bytes += g.node.capacity() * sizeof(Index) + g.begin.capacity() * sizeof(std::uint32_t) +
             g.link.capacity() * sizeof(GhostLink<dim>) + g.spread.capacity() * sizeof(g.spread[0]) +
             g.block_mask.capacity() * sizeof(std::uint64_t) + g.block_first.capacity() * sizeof(std::uint32_t) +
             g.velocity_moment.capacity() * sizeof(Mat<dim>) + g.moment.capacity() * sizeof(int);
  for (const ParticleBuckets<dim>& b : regular_) bytes += b.memory_bytes();
  for (const ParticleBuckets<dim>& b : near_embedded_) bytes += b.memory_bytes();
  for (const std::vector<std::uint32_t>& m : near_masks_) bytes += m.capacity() * sizeof(std::uint32_t);
  for (const LevelStatus& s : status_)
    bytes += s.index.bytes() + s.blocks.capacity() * sizeof(BlockStatus) + s.ghosts.capacity() * sizeof(PendingGhost) +
             s.links.capacity() * sizeof(StatusLink) + s.reached.capacity() * sizeof(s.reached[0]);
  for (const std::vector<BlockKey>& own : own_blocks_) bytes += own.capacity() * sizeof(BlockKey);
  for (const PushTable& t : push_tables_)
    bytes += t.target.capacity() * sizeof(Index) + t.begin.capacity() * sizeof(std::uint32_t) +
             t.source.capacity() * sizeof(PushSource);
  return bytes;
}

template class AdaptiveGrid<2>;
template class AdaptiveGrid<3>;

}  // namespace mpm::adaptive
