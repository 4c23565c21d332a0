#include <mpm/adaptive/refinement.h>
#include <mpm/core/number_text.h>

#include <mpm/core/memory_budget.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include <tbb/parallel_for.h>

#include "lattice_keys.h"

namespace mpm::adaptive {

int levels_of(const Config& scene) {
  const std::optional<Config> cfg = scene.optional_child("adaptive");
  return cfg ? cfg->integer("levels", 2, 1, max_levels) : 1;
}

template <int dim>
std::optional<RefinementSettings<dim>> parse_refinement(const Config& scene, const SceneSettings<dim>& settings) {
  const std::optional<Config> cfg = scene.optional_child("adaptive");
  if (!cfg) return std::nullopt;
  for (int a = 0; a < dim; ++a)
    if (settings.periodic[a])
      scene.fail("periodic", "an adaptive grid (key adaptive) needs a domain without periodic axes");
  if (!std::holds_alternative<QuadraticBSpline>(settings.kernel))
    scene.fail("grid", "an adaptive grid (key adaptive) transfers with GIMP weights: use kernel: quadratic");
  RefinementSettings<dim> r;
  r.levels = levels_of(scene);
  for (const Config& entry : cfg->list("refine")) {
    RefinementRegion<dim> region;
    region.level = entry.integer("level", r.levels - 1, 0, r.levels - 1);
    if (const std::optional<Config> box = entry.optional_child("box")) {
      region.kind = RefinementRegion<dim>::Kind::box;
      region.lo = box->vector<dim>("lo");
      region.hi = box->vector<dim>("hi");
      for (int a = 0; a < dim; ++a) {
        if (!(region.lo[a] < region.hi[a])) box->fail("hi", "every component must exceed the one of lo");
        if (region.lo[a] < settings.domain_lo[a] || region.lo[a] >= settings.domain_hi[a])
          box->fail("lo", "the box must start inside the domain [" + number_text(settings.domain_lo[a]) + ", " +
                              number_text(settings.domain_hi[a]) + ") on axis " + std::to_string(a));
        if (region.hi[a] > settings.domain_hi[a])
          box->fail("hi", "the box must end inside the domain (<= " + number_text(settings.domain_hi[a]) +
                              ") on axis " + std::to_string(a));
      }
    } else if (entry.has("near_colliders")) {
      region.kind = RefinementRegion<dim>::Kind::near_colliders;
      region.distance = entry.number("near_colliders", Range::positive());
    } else {
      entry.fail("box", "a refinement region is a box (box: {lo, hi}) or a band near_colliders: <distance>");
    }
    r.regions.push_back(region);
  }
  r.surface_band = cfg->number("surface_band", 0.0, Range::non_negative());
  r.follow_particles = cfg->flag("follow_particles", true);
  r.padding = cfg->flag("padding", true);
  const std::string walls = cfg->choice("surface_walls", "all", {"none", "rough", "all"});
  r.surface_walls = walls == "none" ? SurfaceWalls::none : walls == "all" ? SurfaceWalls::all : SurfaceWalls::rough;
  if (const std::optional<Config> resample = cfg->optional_child("resample")) {
    ResampleSettings rs;
    rs.d_small = resample->number("d_small", 0.0, Range::non_negative());
    rs.d_medium = resample->number("d_medium", Range::positive());
    rs.d_large = resample->number("d_large", Range::positive());
    rs.every = resample->integer("every", 1, 1, 1000000);
    if (!(rs.d_small < rs.d_medium))
      resample->fail("d_medium",
                     "must exceed d_small = " + number_text(rs.d_small) + " (0 <= d_small < d_medium < d_large)");
    if (!(rs.d_medium < rs.d_large))
      resample->fail("d_large",
                     "must exceed d_medium = " + number_text(rs.d_medium) + " (0 <= d_small < d_medium < d_large)");
    if (resample->has("max_travel")) {
      if (rs.every != 1)
        resample->fail("max_travel", "replaces every = " + std::to_string(rs.every) +
                                         " (resample by the particles' travel or by steps, not both)");
      const double bound = 0.5 * (rs.d_medium - rs.d_small);
      rs.max_travel = resample->number("max_travel", Range::positive());
      if (!(rs.max_travel <= bound))
        resample->fail("max_travel", "must lie in (0, (d_medium - d_small) / 2 = " + number_text(bound) +
                                         "]: a coarse particle may come 2 max_travel nearer the surface "
                                         "before it is split");
    }
    if (r.levels < 2) cfg->fail("levels", "resampling needs two levels or more");
    if (!r.follow_particles)
      cfg->fail("follow_particles", "resampling changes the particle types: the grid must follow them (true)");
    r.resample = rs;
  }
  return r;
}

namespace {

//! True when the cell [lo, hi] meets the region.
template <int dim>
bool meets(const RefinementRegion<dim>& region, const Vec<dim>& lo, const Vec<dim>& hi,
           const geometry::ColliderSet<dim>& colliders) {
  if (region.kind == RefinementRegion<dim>::Kind::box)
    return (lo.array() < region.hi.array()).all() && (hi.array() > region.lo.array()).all();
  // The cell meets the band |phi| <= distance if its centre is within distance plus half its
  // diagonal (phi is a distance).
  const Vec<dim> centre = 0.5 * (lo + hi);
  const double reach = region.distance + 0.5 * (hi - lo).norm();
  for (const auto& c : colliders.colliders())
    if (std::abs(c.phi(centre, 0.0)) <= reach) return true;
  return false;
}

//! Level-0 cells of the tree over the scene's domain.
template <int dim>
IVec<dim> base_cells(const RefinementSettings<dim>& r, const SceneSettings<dim>& settings) {
  const double dx0 = r.coarsest_dx(settings.dx);
  IVec<dim> base;
  for (int a = 0; a < dim; ++a)
    base[a] = static_cast<int>(std::ceil((settings.domain_hi[a] - settings.domain_lo[a]) / dx0 - 1e-9));
  return base;
}

}  // namespace

template <int dim>
void check_refinement_memory(const Config& scene, const RefinementSettings<dim>& r, const SceneSettings<dim>& settings,
                             const geometry::ColliderSet<dim>& colliders) {
  const CellTree<dim> unrefined(settings.domain_lo, base_cells(r, settings), r.coarsest_dx(settings.dx), r.levels);
  // The tree may take half of what still fits: the rest is for the particles and grids that
  // the refinement is for (seeding checks those when it has them).
  const double budget = 0.5 * std::max(0.0, memory_headroom());
  const double cap = budget / kBytesPerRefinedCell;
  const std::vector<Config> entries = scene.child("adaptive").list("refine");
  double count = 0.0;
  for (std::size_t i = 0; i < r.regions.size(); ++i) {
    const RefinementRegion<dim>& region = r.regions[i];
    count += unrefined.count_refinements(
        [&](const Vec<dim>& lo, const Vec<dim>& hi) { return meets(region, lo, hi, colliders) ? region.level : 0; },
        cap - count);
    if (count > cap)
      entries[i].fail(region.kind == RefinementRegion<dim>::Kind::box ? "box" : "near_colliders",
                      "refining to level " + std::to_string(region.level) + " (dx " +
                          number_text(settings.dx * (1 << (r.levels - 1 - region.level))) + " m) refines more than " +
                          number_text(count) + " cells with the regions before it, a tree of more than " +
                          number_text(count * kBytesPerRefinedCell / 1e9) + " GB: the tree may take half of the " +
                          number_text(2.0 * budget / 1e9) +
                          " GB that still fit (the memory available, or --max-memory, less what is held): shrink the "
                          "region, lower its level or coarsen grid.dx");
  }
}

template <int dim>
CellTree<dim> build_tree(const RefinementSettings<dim>& r, const SceneSettings<dim>& settings,
                         const geometry::ColliderSet<dim>& colliders) {
  CellTree<dim> tree(settings.domain_lo, base_cells(r, settings), r.coarsest_dx(settings.dx), r.levels);
  tree.refine_where([&](const Vec<dim>& lo, const Vec<dim>& hi) {
    int target = 0;
    for (const RefinementRegion<dim>& region : r.regions)
      if (meets(region, lo, hi, colliders)) target = std::max(target, region.level);
    return target;
  });
  return tree;
}

namespace {

//! A cell of one level as a sortable key: 21 bits per axis (2^21 cells per axis and level).
constexpr int cell_key_bits = 21;
template <int dim>
std::uint64_t cell_key(const IVec<dim>& cell) {
  std::uint64_t key = 0;
  for (int a = dim - 1; a >= 0; --a) key = (key << cell_key_bits) | static_cast<std::uint64_t>(cell[a]);
  return key;
}

template <int dim>
IVec<dim> key_cell(std::uint64_t key) {
  IVec<dim> cell;
  for (int a = 0; a < dim; ++a, key >>= cell_key_bits)
    cell[a] = static_cast<int>(key & ((std::uint64_t{1} << cell_key_bits) - 1));
  return cell;
}

//! A direct-mapped cache of the keys seen last: a cheap filter for the repeats of neighbours
//! (particles of a cell come in runs, interleaved with a few other cells' runs).
class RecentKeys {
public:
  RecentKeys() { slots_.fill(~std::uint64_t{0}); }
  //! False when `key` is among the keys seen last; otherwise remembers it.
  bool fresh(std::uint64_t key) {
    std::uint64_t& slot = slots_[(key * 0x9e3779b97f4a7c15ull) >> 54];
    if (slot == key) return false;
    slot = key;
    return true;
  }

private:
  std::array<std::uint64_t, 1024> slots_;
};

//! Collects distinct keys: RecentKeys drops most repeats before the sort that drops the rest.
class DistinctKeys {
public:
  void add(std::uint64_t key) {
    if (recent_.fresh(key)) keys_.push_back(key);
  }
  //! Adds the keys `other` holds.
  void absorb(const DistinctKeys& other) { absorb_keys(other.keys_); }
  void absorb_keys(const std::vector<std::uint64_t>& keys) { keys_.insert(keys_.end(), keys.begin(), keys.end()); }
  //! The keys added (cell_key<dim>), sorted, each once.
  template <int dim>
  std::vector<std::uint64_t> take() {
    sort_unique_points<dim>(keys_, cell_key_bits);
    return std::move(keys_);
  }

private:
  RecentKeys recent_;
  std::vector<std::uint64_t> keys_;
};

//! Refines from the leaf that holds level-q cell `cell` down to `cell` itself.
template <int dim>
void refine_down_to(CellTree<dim>& tree, const IVec<dim>& cell, int q) {
  for (int level = tree.leaf_of(IVec<dim>(cell * tree.scale(q))).level; level <= q; ++level)
    tree.refine(level, IVec<dim>(cell / (1 << (q - level))));
}

//! Level q >= 1 of refine_around_particles: the level-(q-1) cell of every type-q particle (types
//! beyond the finest level count as the finest) is refined, with the coarser leaf that holds
//! it. With `padding`, so is every level-(q-1) cell next to one of those (3^dim neighbourhood)
//! unless a coarser particle's box (taken as its whole cell of its level around it: the box is
//! never wider) may reach into it or into the coarser leaf that would have to be split for it.
//! So the fine region reaches one cell of the next coarser level past its particles into empty
//! space, and their stencils (1.5 level-q cells wide) end on real level-q nodes: no ghost nodes
//! there. No particle lands in a finer leaf than without padding, so none becomes irregular.
//! Particles outside the domain (or not finite) are left alone, as prepare() reports them.
template <int dim>
void refine_level(CellTree<dim>& tree, const std::vector<Vec<dim>>& x, const std::vector<std::uint16_t>& type, int q,
                  bool padding) {
  // The level-l cell of y; with `upper`, the last one an open box ending at y meets.
  const auto cell_at = [&](int level, const Vec<dim>& y, bool upper = false) {
    IVec<dim> c;
    for (int a = 0; a < dim; ++a) {
      const double s = (y[a] - tree.origin()[a]) / tree.dx(level);
      c[a] = std::clamp(static_cast<int>(upper ? std::ceil(s) - 1.0 : std::floor(s)), 0,
                        (tree.base_cells()[a] << level) - 1);
    }
    return c;
  };
  const auto inside = [&](const Vec<dim>& y) {
    for (int a = 0; a < dim; ++a) {
      const double s = (y[a] - tree.origin()[a]) / tree.dx(0);
      if (!(s >= 0.0 && s < tree.base_cells()[a])) return false;  // also false for NaN
    }
    return true;
  };
  // Per chunk of particles, in parallel: the level-(q-1) cells with type-q particles, and the
  // cells that each coarser particle's box meets on level min(t + 1, q - 1) for its type t
  // (3^dim at most: the box is no wider than two cells of level t + 1). The sets do not depend
  // on the chunks.
  struct Found {
    DistinctKeys holding;
    std::vector<DistinctKeys> met;
  };
  constexpr std::size_t chunk = 16384;
  std::vector<Found> found((x.size() + chunk - 1) / chunk);
  tbb::parallel_for(std::size_t{0}, found.size(), [&](std::size_t k) {
    Found& f = found[k];
    f.met.resize(static_cast<std::size_t>(q));
    for (std::size_t p = k * chunk; p < std::min(x.size(), (k + 1) * chunk); ++p) {
      const int t = std::min<int>(type[p], tree.finest());
      if (t > q || (t < q && !padding) || !inside(x[p])) continue;
      if (t == q) {
        f.holding.add(cell_key<dim>(cell_at(q - 1, x[p])));
      } else {
        const int level = std::min(t + 1, q - 1);
        const double r = 0.5 * tree.dx(t);
        for_each_in_box<dim>(cell_at(level, Vec<dim>(x[p].array() - r)),
                             cell_at(level, Vec<dim>(x[p].array() + r), true),
                             [&](const IVec<dim>& c) { f.met[level].add(cell_key<dim>(c)); });
      }
    }
  });
  DistinctKeys holding;
  for (const Found& f : found) holding.absorb(f.holding);
  const std::vector<std::uint64_t> held = holding.take<dim>();
  for (const std::uint64_t key : held) refine_down_to(tree, key_cell<dim>(key), q - 1);  // the particles' cells
  if (!padding || held.empty()) return;

  // met[l]: the level-l cells a coarser box meets; reached[l]: those and the level-l cells
  // that hold one of them (a leaf not to be split).
  std::vector<std::vector<std::uint64_t>> met(static_cast<std::size_t>(q)), reached(static_cast<std::size_t>(q));
  for (int l = q - 1; l >= 0; --l) {
    DistinctKeys level_met, level_reached;
    for (const Found& f : found) level_met.absorb(f.met[l]);
    met[l] = level_met.take<dim>();
    level_reached.absorb_keys(met[l]);
    if (l + 1 < q)
      for (const std::uint64_t key : reached[l + 1])
        level_reached.add(cell_key<dim>(IVec<dim>(key_cell<dim>(key) / 2)));
    reached[l] = level_reached.take<dim>();
  }
  const auto listed = [](const std::vector<std::uint64_t>& keys, const IVec<dim>& c) {
    return std::binary_search(keys.begin(), keys.end(), cell_key<dim>(c));
  };
  const auto box_may_meet = [&](const IVec<dim>& c) {  // c of level q - 1
    for (int l = 0; l < q; ++l)
      if (listed(met[l], IVec<dim>(c / (1 << (q - 1 - l))))) return true;
    return false;
  };
  IVec<dim> last;  // of level q - 1 in the domain
  for (int a = 0; a < dim; ++a) last[a] = (tree.base_cells()[a] << (q - 1)) - 1;
  // The candidates around the held cells, per chunk of them in parallel (the tree is only read).
  std::vector<DistinctKeys> candidates((held.size() + 1023) / 1024);
  tbb::parallel_for(std::size_t{0}, candidates.size(), [&](std::size_t k) {
    RecentKeys tested;  // neighbouring held cells share most of their neighbours
    for (std::size_t i = k * 1024; i < std::min(held.size(), (k + 1) * 1024); ++i) {
      const IVec<dim> cell = key_cell<dim>(held[i]);
      for_each_in_box<dim>(IVec<dim>(cell.array() - 1).cwiseMax(0), IVec<dim>(cell.array() + 1).cwiseMin(last),
                           [&](const IVec<dim>& c) {
                             if (!tested.fresh(cell_key<dim>(c)) || tree.is_refined(q - 1, c) || box_may_meet(c))
                               return;
                             const CellId<dim> leaf = tree.leaf_of(IVec<dim>(c * tree.scale(q - 1)));
                             if (leaf.level == q - 1 || !listed(reached[leaf.level], leaf.cell))
                               candidates[k].add(cell_key<dim>(c));
                           });
    }
  });
  DistinctKeys padded;
  for (const DistinctKeys& c : candidates) padded.absorb(c);
  // In key order: the same tree whatever the particles' order.
  for (const std::uint64_t key : padded.take<dim>()) refine_down_to(tree, key_cell<dim>(key), q - 1);
}

}  // namespace

template <int dim>
void refine_around_particles(CellTree<dim>& tree, const std::vector<Vec<dim>>& x,
                             const std::vector<std::uint16_t>& type, bool padding) {
  // Coarse to fine: a level's pass finds the coarser cells its particles need already split.
  for (int q = 1; q <= tree.finest(); ++q) refine_level(tree, x, type, q, padding);
}

template void refine_around_particles(CellTree<2>&, const std::vector<Vec<2>>&, const std::vector<std::uint16_t>&,
                                      bool);
template void refine_around_particles(CellTree<3>&, const std::vector<Vec<3>>&, const std::vector<std::uint16_t>&,
                                      bool);
template std::optional<RefinementSettings<2>> parse_refinement(const Config&, const SceneSettings<2>&);
template std::optional<RefinementSettings<3>> parse_refinement(const Config&, const SceneSettings<3>&);
template CellTree<2> build_tree(const RefinementSettings<2>&, const SceneSettings<2>&, const geometry::ColliderSet<2>&);
template CellTree<3> build_tree(const RefinementSettings<3>&, const SceneSettings<3>&, const geometry::ColliderSet<3>&);
template void check_refinement_memory(const Config&, const RefinementSettings<2>&, const SceneSettings<2>&,
                                      const geometry::ColliderSet<2>&);
template void check_refinement_memory(const Config&, const RefinementSettings<3>&, const SceneSettings<3>&,
                                      const geometry::ColliderSet<3>&);

}  // namespace mpm::adaptive
