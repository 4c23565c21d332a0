// Type-driven refinement (adaptive/refinement.h, refine_around_particles), with and without
// padding, on a slab of finest particles between empty space (above) and coarse particles
// (below), in 2D and 3D on three levels:
//  - every particle lies in a leaf of at least its type's level, with and without padding;
//  - padding only adds refinement, and no particle's transfer level (the finest leaf its box
//    meets) changes: no particle becomes irregular;
//  - with padding, every finest particle away from the coarse ones has only finest cells within
//    1.5 finest cells of it (its stencil has no embedded node), which is not so without;
//  - the tree does not depend on the particles' order; particles outside the domain or not
//    finite refine nothing.
// And on random particles of random types (beyond the finest too) over five levels with a
// static refinement box: without padding the tree is the one of refining each particle's leaf
// in turn (the loop the library ran before), and padding changes no transfer level.
#include <mpm/adaptive/cell_set.h>
#include <mpm/adaptive/refinement.h>

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <random>
#include <set>
#include <vector>

using namespace mpm;
using namespace mpm::adaptive;

namespace {

constexpr int kLevels = 3;

//! Level-0 cells of size 1 over [0, 8)^dim. Finest particles (type 2, two per finest cell per
//! axis) fill y in [4, 4.5); coarse particles (type 0, one per level-0 cell) sit below, in
//! y in [1, 3), and four nearer the slab.
template <int dim>
void build(std::vector<Vec<dim>>& x, std::vector<std::uint16_t>& type) {
  const double fine = 0.125;  // half a finest cell
  IVec<dim> n = IVec<dim>::Constant(64);
  n[1] = 4;
  for_each_in_box<dim>(IVec<dim>::Zero(), IVec<dim>(n.array() - 1), [&](const IVec<dim>& i) {
    Vec<dim> p = (i.template cast<double>().array() + 0.5) * fine;
    p[1] += 4.0;
    x.push_back(p);
    type.push_back(2);
  });
  IVec<dim> m = IVec<dim>::Constant(8);
  m[1] = 2;
  for_each_in_box<dim>(IVec<dim>::Zero(), IVec<dim>(m.array() - 1), [&](const IVec<dim>& i) {
    Vec<dim> p = i.template cast<double>().array() + 0.5;
    p[1] += 1.0;
    x.push_back(p);
    type.push_back(0);
  });
  // Coarse particles near the slab: two below it; one on the corner of its level-0 cell, which
  // padding must not split for the empty level-1 cell next to the slab that it holds; one on
  // the slab, in a level-1 leaf next to it.
  for (const auto& [along, height] :
       {std::pair{1.5, 3.4}, std::pair{5.5, 3.4}, std::pair{6.0, 3.0}, std::pair{6.5, 4.75}}) {
    Vec<dim> p = Vec<dim>::Constant(2.5);
    p[0] = along;
    p[1] = height;
    x.push_back(p);
    type.push_back(0);
  }
}

template <int dim>
CellTree<dim> refined(const std::vector<Vec<dim>>& x, const std::vector<std::uint16_t>& type, bool padding) {
  CellTree<dim> tree(Vec<dim>::Zero(), IVec<dim>::Constant(8), 1.0, kLevels);
  refine_around_particles(tree, x, type, padding);
  return tree;
}

//! The finest level of the leaves a particle's box (half a cell of its type per axis) meets.
template <int dim>
int transfer_level(const CellTree<dim>& tree, const Vec<dim>& x, int type) {
  const double half = 0.25 * tree.dx(type);
  return tree.finest_level_in(Vec<dim>(x.array() - half), Vec<dim>(x.array() + half));
}

//! Whether every finest cell within 1.5 finest cells of x lies in a finest leaf.
template <int dim>
bool stencil_on_finest_leaves(const CellTree<dim>& tree, const Vec<dim>& x) {
  const double h = tree.dx(tree.finest());
  IVec<dim> lo, hi;
  for (int a = 0; a < dim; ++a) {
    lo[a] = static_cast<int>(std::floor(x[a] / h - 1.5));
    hi[a] = static_cast<int>(std::floor(x[a] / h + 1.5));
  }
  bool all = true;
  for_each_in_box<dim>(lo, hi, [&](const IVec<dim>& f) { all = all && tree.leaf_of(f).level == tree.finest(); });
  return all;
}

template <int dim>
void check_padding() {
  std::vector<Vec<dim>> x;
  std::vector<std::uint16_t> type;
  build<dim>(x, type);
  const CellTree<dim> plain = refined<dim>(x, type, false), padded = refined<dim>(x, type, true);
  CHECK_FALSE(plain == padded);
  for (const CellId<dim>& c : plain.refined_difference(padded))  // padding only adds refined cells
    CHECK(padded.is_refined(c.level, c.cell));
  int ghost_free_plain = 0, ghost_free_padded = 0, away = 0;
  for (std::size_t p = 0; p < x.size(); ++p) {
    CHECK(plain.leaf_at(x[p]).level >= type[p]);
    CHECK(padded.leaf_at(x[p]).level >= type[p]);
    CHECK(transfer_level(padded, x[p], type[p]) == transfer_level(plain, x[p], type[p]));
    // Finest particles 1.5 level-0 cells or more (in x) from the coarse ones below the slab, and
    // a level-0 cell or more from the domain's sides.
    const bool inside = dim == 2 || (x[p][dim - 1] > 1.0 && x[p][dim - 1] < 7.0);
    if (type[p] == 2 && x[p][0] > 3.0 && x[p][0] < 4.0 && inside) {
      ++away;
      ghost_free_plain += stencil_on_finest_leaves(plain, x[p]);
      ghost_free_padded += stencil_on_finest_leaves(padded, x[p]);
    }
  }
  REQUIRE(away > 0);
  CHECK(ghost_free_padded == away);
  CHECK(ghost_free_plain == 0);  // without padding every row's stencil reaches a coarse cell (slab 4 cells thick)

  // The particles in another order refine the same tree.
  std::vector<std::size_t> order(x.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), std::mt19937(7));
  std::vector<Vec<dim>> xs;
  std::vector<std::uint16_t> ts;
  for (std::size_t i : order) {
    xs.push_back(x[i]);
    ts.push_back(type[i]);
  }
  CHECK(refined<dim>(xs, ts, true) == padded);

  // Particles outside the domain or not finite refine nothing (prepare() reports them): a
  // finest one and a coarse one next to the slab, beyond the domain's side, and a finest NaN.
  Vec<dim> beside = Vec<dim>::Constant(2.5);
  beside[0] = -0.1;
  beside[1] = 4.25;
  xs.insert(xs.end(), {beside, beside, Vec<dim>::Constant(std::nan(""))});
  ts.insert(ts.end(), {2, 0, 2});
  CHECK(refined<dim>(xs, ts, true) == padded);
  CHECK(refined<dim>(xs, ts, false) == plain);
}

//! Random particles over [0, 4)^dim on five levels (a static box refined to level 2): the tree
//! without padding against refining each particle's leaf in turn; with padding, the same
//! transfer level for every particle.
template <int dim>
bool check_random(unsigned seed) {
  constexpr int levels = 5;
  CellTree<dim> unrefined(Vec<dim>::Zero(), IVec<dim>::Constant(4), 1.0, levels);
  unrefined.refine_where([](const Vec<dim>& lo, const Vec<dim>&) { return lo.maxCoeff() < 1.0 ? 2 : 0; });
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> position(0.0, 4.0);
  std::vector<Vec<dim>> x;
  std::vector<std::uint16_t> type;
  for (int p = 0; p < 300; ++p) {
    Vec<dim> y;
    for (int a = 0; a < dim; ++a) y[a] = position(rng);
    if (p % 3 == 0) y = (y / 2.0).array() + 1.0;  // clusters: coarse and fine particles meet
    x.push_back(y);
    type.push_back(static_cast<std::uint16_t>(rng() % (levels + 2)));
  }
  CellTree<dim> serial = unrefined;
  for (std::size_t p = 0; p < x.size(); ++p) serial.refine_to(x[p], type[p]);  // clamped to the finest
  CellTree<dim> plain = unrefined, padded = unrefined;
  refine_around_particles(plain, x, type, false);
  refine_around_particles(padded, x, type, true);
  CHECK(plain == serial);
  for (std::size_t p = 0; p < x.size(); ++p) {
    const int t = std::min<int>(type[p], levels - 1);
    CHECK(transfer_level(padded, x[p], t) == transfer_level(plain, x[p], t));
  }
  return !(padded == plain);  // whether padding refined anything
}

}  // namespace

TEST_CASE("padding refines around the finest particles into empty space only, in 2D and 3D") {
  check_padding<2>();
  check_padding<3>();
}

TEST_CASE(
    "on random particles and five levels, refinement equals the particle-by-particle loop, padding keeps "
    "transfer levels") {
  int padded_2d = 0, padded_3d = 0;
  for (unsigned seed = 1; seed <= 4; ++seed) {
    padded_2d += check_random<2>(seed);
    padded_3d += check_random<3>(seed);
  }
  CHECK(padded_2d > 0);  // the random scenes do leave room to pad
  CHECK(padded_3d > 0);
}

// The tree's per-level cell set (cell_set.h: bit masks of bricks) against std::set on random
// cells spread over many bricks and clustered in a few: membership, size, iteration and the
// difference of two sets, in 2D and 3D.
template <int dim>
void check_cell_set(std::uint32_t seed) {
  std::mt19937 rng(seed);
  const auto key = [](const IVec<dim>& c) { return std::vector<int>(c.data(), c.data() + dim); };
  for (const int extent : {9, 200}) {  // a few bricks, densely; many, sparsely
    std::uniform_int_distribution<int> coord(0, extent - 1);
    CellSet<dim> a, b;
    std::set<std::vector<int>> ref_a, ref_b;
    for (int i = 0; i < 3000; ++i) {
      IVec<dim> c;
      for (int ax = 0; ax < dim; ++ax) c[ax] = coord(rng);
      CHECK(a.insert(c) == ref_a.insert(key(c)).second);
      if (i % 3 == 0) {
        for (int ax = 0; ax < dim; ++ax) c[ax] = coord(rng);
        b.insert(c);
        ref_b.insert(key(c));
      }
    }
    CHECK(a.size() == ref_a.size());
    std::set<std::vector<int>> seen;
    a.for_each([&](const IVec<dim>& c) { CHECK(seen.insert(key(c)).second); });
    CHECK(seen == ref_a);
    for (int i = 0; i < 3000; ++i) {
      IVec<dim> c;
      for (int ax = 0; ax < dim; ++ax) c[ax] = coord(rng) + (i % 2 ? 0 : extent);  // half outside the range
      CHECK(a.contains(c) == (ref_a.count(key(c)) > 0));
    }
    CHECK_FALSE(a.contains(IVec<dim>::Constant(-1)));
    std::set<std::vector<int>> only_a, expected;
    a.for_each_not_in(b, [&](const IVec<dim>& c) { only_a.insert(key(c)); });
    std::set_difference(ref_a.begin(), ref_a.end(), ref_b.begin(), ref_b.end(),
                        std::inserter(expected, expected.end()));
    CHECK(only_a == expected);
  }
}

TEST_CASE("the tree's cell sets agree with std::set in 2D and 3D") {
  check_cell_set<2>(7);
  check_cell_set<3>(11);
}
