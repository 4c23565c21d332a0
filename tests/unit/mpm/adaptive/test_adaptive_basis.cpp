// The constrained T-junction basis and its GIMP weights (Gao et al. 2017, sec. 5.2 and 6.1) on
// random non-graded quadtrees and octrees of 4 levels:
//  - N_i: partition of unity, non-negativity, linear reproduction, and continuity across every
//    kind of leaf face (the values from the two leaves agree);
//  - w_ip from the ghost-node transfer (uniform weights on one level, pushed by embedding
//    weights, eq. 15) equal the GIMP convolution of N_i over the particle box, computed
//    independently by Gauss quadrature on the finest lattice;
//  - w_ip: partition of unity, non-negativity, linear reproduction; grad w_ip against central
//    differences; w and grad w continuous where the particle box enters a finer leaf;
//  - the free T-junction basis of Lian et al. (sec. 5.1, eq. 9-10) goes negative where the
//    constrained basis does not;
//  - the leaf lookups from a hint leaf find what the walks from the roots find.
#include <mpm/adaptive/adaptive_transfer.h>
#include <mpm/adaptive/constrained_basis.h>

#include <doctest/doctest.h>

#include "random_tree.h"

#include <map>
#include <random>

using namespace mpm;
using namespace mpm::adaptive;

namespace {

template <int dim>
using PointMap = std::map<std::vector<int>, double>;

template <int dim>
std::vector<int> key(const IVec<dim>& p) {
  return std::vector<int>(p.data(), p.data() + dim);
}

template <int dim>
PointMap<dim> as_map(const std::vector<NodeWeight<dim>>& nw) {
  PointMap<dim> m;
  for (const auto& n : nw) m[key<dim>(n.point)] += n.weight;
  return m;
}

// A random position at least `margin` [m] inside the domain.
template <int dim>
Vec<dim> random_point(const CellTree<dim>& tree, std::mt19937& rng, double margin = 0.0) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Vec<dim> x;
  for (int a = 0; a < dim; ++a)
    x[a] = tree.origin()[a] + margin + u(rng) * (tree.base_cells()[a] * tree.dx(0) - 2 * margin);
  return x;
}

// Particles of every type keep their GIMP box (side <= dx_0) and their stencil in the grid.
template <int dim>
double particle_margin(const CellTree<dim>& tree) {
  return 0.6 * tree.dx(0);
}

// GIMP weights (eq. 5) of the constrained basis over the box [x - L/2, x + L/2] (clipped to the
// domain), by 2-point Gauss quadrature on each piece of the box cut by the finest lattice:
// N_i is multilinear there, so the rule is exact.
template <int dim>
PointMap<dim> gimp_by_quadrature(const CellTree<dim>& tree, const Vec<dim>& x, double L) {
  const double df = tree.dx(tree.finest());
  const Vec<dim> lo = x.array() - 0.5 * L, hi = x.array() + 0.5 * L;
  std::vector<std::vector<double>> nodes(dim), weights(dim);  // 1D rule per axis
  for (int a = 0; a < dim; ++a) {
    const double o = tree.origin()[a];
    double s = lo[a];
    while (s < hi[a]) {
      const double e = std::min(hi[a], o + (std::floor((s - o) / df + 1e-12) + 1) * df);
      const double m = 0.5 * (s + e), r = 0.5 * (e - s) / std::sqrt(3.0);
      for (double q : {m - r, m + r}) {
        nodes[a].push_back(q);
        weights[a].push_back(0.5 * (e - s) / L);
      }
      s = e;
    }
  }
  PointMap<dim> w;
  std::vector<int> idx(dim, 0);
  while (true) {
    Vec<dim> q;
    double wq = 1.0;
    for (int a = 0; a < dim; ++a) {
      q[a] = nodes[a][idx[a]];
      wq *= weights[a][idx[a]];
    }
    for (const auto& n : basis_at(tree, q)) w[key<dim>(n.point)] += wq * n.weight;
    int a = 0;
    for (; a < dim; ++a) {
      if (++idx[a] < static_cast<int>(nodes[a].size())) break;
      idx[a] = 0;
    }
    if (a == dim) break;
  }
  return w;
}

// Real weights of particles at `xs` (type `type`) by lattice point: w and grad w.
template <int dim>
struct Weights {
  PointMap<dim> w;
  std::map<std::vector<int>, Vec<dim>> grad;
};
template <int dim>
std::vector<Weights<dim>> transfer_weights(AdaptiveGrid<dim>& grid, const std::vector<Vec<dim>>& xs, int type) {
  grid.prepare(xs, std::vector<std::uint16_t>(xs.size(), static_cast<std::uint16_t>(type)));
  std::vector<Weights<dim>> out(xs.size());
  for (std::size_t p = 0; p < xs.size(); ++p)
    for (const auto& rw : real_weights(grid, grid.transfer_level(p), grid.half_cells(p), xs[p])) {
      const IVec<dim> point =
          grid.level(rw.level).node_coord(static_cast<std::size_t>(rw.index)) * grid.tree().scale(rw.level);
      out[p].w[key<dim>(point)] += rw.w;
      out[p].grad[key<dim>(point)] = rw.grad;
    }
  return out;
}

template <int dim>
Vec<dim> lattice_position(const CellTree<dim>& tree, const std::vector<int>& k) {
  IVec<dim> p;
  for (int a = 0; a < dim; ++a) p[a] = k[a];
  return tree.position(p);
}

template <int dim>
void check_basis(unsigned seed) {
  const CellTree<dim> tree = test::random_tree<dim>(seed, 4, 3);
  std::mt19937 rng(seed + 1);
  for (int trial = 0; trial < 300; ++trial) {
    const Vec<dim> x = random_point(tree, rng);
    const auto N = basis_at(tree, x);
    REQUIRE(!N.empty());
    double sum = 0.0;
    Vec<dim> first = Vec<dim>::Zero();
    for (const auto& n : N) {
      CHECK(n.weight >= -1e-15);
      CHECK(home_level(tree, n.point) == n.level);  // only real nodes carry a basis function
      sum += n.weight;
      first += n.weight * tree.position(n.point);
    }
    CHECK(sum == doctest::Approx(1.0).epsilon(1e-13));
    CHECK((first - x).norm() < 1e-13);
  }
}

// Continuity: a point on a face of a leaf, reached from that leaf and from the leaf across
// the face, has the same basis values.
template <int dim>
void check_continuity(unsigned seed) {
  const CellTree<dim> tree = test::random_tree<dim>(seed, 4, 3);
  std::mt19937 rng(seed + 2);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<std::pair<int, IVec<dim>>> leaves;
  tree.for_each_leaf([&](int level, const IVec<dim>& cell) { leaves.emplace_back(level, cell); });
  int faces = 0, level_jumps = 0;
  for (const auto& [level, cell] : leaves) {
    for (int axis = 0; axis < dim; ++axis) {
      Vec<dim> x = tree.origin() +
                   tree.dx(level) * (cell.template cast<double>() + Vec<dim>::NullaryExpr([&] { return u(rng); }));
      x[axis] = tree.origin()[axis] + tree.dx(level) * (cell[axis] + 1);  // on the upper face
      Vec<dim> across = x;
      across[axis] += 1e-9 * tree.dx(tree.finest());
      const CellId<dim> other = tree.leaf_at(across);
      if (other.level < 0) continue;  // domain boundary
      ++faces;
      level_jumps += other.level != level;
      const auto a = as_map<dim>(basis_in_leaf(tree, level, cell, x));
      const auto b = as_map<dim>(basis_in_leaf(tree, other.level, other.cell, x));
      PointMap<dim> diff = a;
      for (const auto& [k, w] : b) diff[k] -= w;
      for (const auto& [k, d] : diff) CHECK(std::abs(d) < 1e-12);
    }
  }
  CHECK(faces > 20);
  CHECK(level_jumps > 5);
}

template <int dim>
void check_gimp_weights(unsigned seed) {
  AdaptiveGrid<dim> grid(test::random_tree<dim>(seed, 4, 3));
  const CellTree<dim>& tree = grid.tree();
  std::mt19937 rng(seed + 3);
  std::uniform_int_distribution<int> type(0, tree.finest());
  int transitions = 0;
  for (int trial = 0; trial < (dim == 2 ? 60 : 12); ++trial) {
    const int t = type(rng);
    const Vec<dim> x = random_point(tree, rng, particle_margin(tree));
    const Weights<dim> got = transfer_weights<dim>(grid, {x}, t)[0];
    transitions += grid.transfer_level(0) != t;
    const PointMap<dim> want = gimp_by_quadrature(tree, x, grid.particle_size(t));
    double sum = 0.0;
    Vec<dim> first = Vec<dim>::Zero();
    for (const auto& [k, w] : got.w) {
      CHECK(w >= -1e-15);
      sum += w;
      first += w * lattice_position<dim>(tree, k);
      const auto it = want.find(k);
      CHECK(std::abs(w - (it == want.end() ? 0.0 : it->second)) < 1e-12);
    }
    for (const auto& [k, w] : want) CHECK((got.w.count(k) == 1 || std::abs(w) < 1e-12));
    CHECK(sum == doctest::Approx(1.0).epsilon(1e-13));
    CHECK((first - x).norm() < 1e-12 * tree.dx(0));
  }
  CHECK(transitions > 0);  // some particles transferred on a level finer than their type
}

// grad w against central differences of w, at random points and where the particle box is
// about to enter a finer leaf (the transfer level changes there).
template <int dim>
void check_gradients(unsigned seed) {
  AdaptiveGrid<dim> grid(test::random_tree<dim>(seed, 4, 3));
  const CellTree<dim>& tree = grid.tree();
  std::mt19937 rng(seed + 4);
  const double d = 1e-6 * tree.dx(tree.finest());
  double worst = 0.0;
  for (int trial = 0; trial < (dim == 2 ? 40 : 10); ++trial) {
    const int t = trial % 2;  // coarse particles, which meet finer leaves
    const Vec<dim> x = random_point(tree, rng, particle_margin(tree));
    std::vector<Vec<dim>> xs{x};
    for (int a = 0; a < dim; ++a)
      for (double s : {1.0, -1.0}) {
        xs.push_back(x);
        xs.back()[a] += s * d;
      }
    const auto W = transfer_weights<dim>(grid, xs, t);
    for (const auto& [k, g] : W[0].grad) {
      for (int a = 0; a < dim; ++a) {
        auto at = [&](std::size_t p) {
          const auto it = W[p].w.find(k);
          return it == W[p].w.end() ? 0.0 : it->second;
        };
        const double fd = (at(1 + 2 * a) - at(2 + 2 * a)) / (2 * d);
        worst = std::max(worst, std::abs(fd - g[a]) * tree.dx(0));
      }
    }
  }
  CHECK(worst < 1e-6);
}

// w and grad w are continuous (C1) across the positions where the transfer level changes:
// the particle box touches a finer leaf on one side only.
template <int dim>
void check_level_switch(unsigned seed) {
  AdaptiveGrid<dim> grid(test::random_tree<dim>(seed, 4, 3));
  const CellTree<dim>& tree = grid.tree();
  std::vector<std::pair<int, IVec<dim>>> fine;
  tree.for_each_leaf([&](int level, const IVec<dim>& cell) {
    if (level == tree.finest()) fine.emplace_back(level, cell);
  });
  REQUIRE(!fine.empty());
  const int type = tree.finest() - 2;
  const double L = grid.particle_size(type), eps = 1e-7 * tree.dx(tree.finest());
  int switches = 0;
  double worst_w = 0.0, worst_grad = 0.0;
  for (std::size_t i = 0; i < fine.size() && switches < 20; ++i) {
    const Vec<dim> lo = tree.origin() + tree.dx(tree.finest()) * fine[i].second.template cast<double>();
    // The box's lower face on the fine leaf's upper face, moving along axis 0.
    Vec<dim> x = lo + Vec<dim>::Constant(0.5 * tree.dx(tree.finest()));
    x[0] = lo[0] + tree.dx(tree.finest()) + 0.5 * L;
    const Vec<dim> hi = tree.origin() + tree.dx(0) * tree.base_cells().template cast<double>();
    if ((x.array() - particle_margin(tree) < tree.origin().array()).any() ||
        (x.array() + particle_margin(tree) > hi.array()).any())
      continue;
    Vec<dim> before = x, after = x;
    before[0] -= eps;
    after[0] += eps;
    const auto W = transfer_weights<dim>(grid, {before, after}, type);
    if (grid.transfer_level(0) == grid.transfer_level(1)) continue;
    ++switches;
    std::map<std::vector<int>, int> keys;
    for (const auto& [k, w] : W[0].w) keys[k] = 1;
    for (const auto& [k, w] : W[1].w) keys[k] = 1;
    for (const auto& [k, one] : keys) {
      auto w_of = [&](int p) { return W[p].w.count(k) ? W[p].w.at(k) : 0.0; };
      auto g_of = [&](int p) { return W[p].grad.count(k) ? W[p].grad.at(k) : Vec<dim>(Vec<dim>::Zero()); };
      // No jump in w: the change across 2 eps is the one the gradient predicts.
      worst_w = std::max(worst_w, std::abs(w_of(1) - w_of(0) - 0.5 * (g_of(0) + g_of(1))[0] * 2 * eps));
      worst_grad = std::max(worst_grad, (g_of(0) - g_of(1)).norm() * tree.dx(tree.finest()));
    }
  }
  CHECK(switches > 0);
  CHECK(worst_w < 1e-13);    // round-off of w (a jump would be O(1))
  CHECK(worst_grad < 1e-6);  // grad w is C0: a change O(eps / dx), scaled by dx_finest
}

// leaf_at(x, hint) and finest_level_in(lo, hi, last_leaf) against the walks from the roots,
// with a hint of no cell, the leaf of a nearby point (the loops' case) and of a random point.
template <int dim>
void check_leaf_hints(unsigned seed) {
  const CellTree<dim> tree = test::random_tree<dim>(seed, 4, 3);
  std::mt19937 rng(seed + 100);
  std::uniform_real_distribution<double> u(-0.5, 2.5), step(-0.05, 0.05);
  Vec<dim> x, prev;
  for (int a = 0; a < dim; ++a) prev[a] = u(rng);
  int differing = 0;
  for (int i = 0; i < 4000; ++i) {
    for (int a = 0; a < dim; ++a) x[a] = i % 7 == 0 ? u(rng) : std::clamp(prev[a] + step(rng), -0.5, 2.49);
    const IVec<dim> finest_cell = ((x - tree.origin()) / tree.dx(tree.finest())).array().floor().template cast<int>();
    const CellId<dim> truth = tree.leaf_of(finest_cell);  // the walk from the root
    Vec<dim> far;
    for (int a = 0; a < dim; ++a) far[a] = u(rng);
    for (CellId<dim> hint : {CellId<dim>{}, tree.leaf_at(prev), tree.leaf_at(far)}) {
      const CellId<dim> found = tree.leaf_at(x, hint);
      CHECK(found.level == truth.level);
      CHECK(found.cell == truth.cell);
      differing += hint.level != truth.level || hint.cell != truth.cell;
      const Vec<dim> h = Vec<dim>::Constant(0.01 * (i % 5));
      CHECK(tree.finest_level_in(x - h, x + h, hint) == tree.finest_level_in(x - h, x + h));
    }
    prev = x;
  }
  CHECK(differing > 1000);  // the hints often miss, so the walks below them are exercised
}

// Lian et al.'s free T-junction basis (eq. 9-10) on a coarse cell [-1, 1]^2 with T-junctions b
// = (1, 0) and d = (0, 1): the corner function N_c = H_c - N_b / 2 - N_d / 2.
double free_tjunction_Nc(double x, double y) {
  const double Nb = 0.5 * (1 + x) * (1 - std::abs(y)), Nd = 0.5 * (1 - std::abs(x)) * (1 + y);
  const double Hc = 0.25 * (1 + x) * (1 - y);
  return Hc - 0.5 * Nb - 0.5 * Nd;
}

}  // namespace

TEST_CASE("constrained basis: partition of unity, non-negativity, linear reproduction (2D, 3D)") {
  for (unsigned seed : {1u, 2u, 3u}) check_basis<2>(seed);
  for (unsigned seed : {4u, 5u}) check_basis<3>(seed);
}

TEST_CASE("constrained basis: continuous across faces between leaves of any level difference") {
  for (unsigned seed : {1u, 2u, 3u}) check_continuity<2>(seed);
  for (unsigned seed : {4u, 5u}) check_continuity<3>(seed);
}

TEST_CASE("ghost-node GIMP weights equal the GIMP convolution of the constrained basis (eq. 4, 15)") {
  for (unsigned seed : {1u, 2u, 3u}) check_gimp_weights<2>(seed);
  for (unsigned seed : {4u, 5u}) check_gimp_weights<3>(seed);
}

TEST_CASE("GIMP weight gradients against central differences") {
  for (unsigned seed : {1u, 2u}) check_gradients<2>(seed);
  check_gradients<3>(4u);
}

TEST_CASE("weights are C1 where a particle's box enters a finer leaf") {
  for (unsigned seed : {1u, 2u, 3u}) check_level_switch<2>(seed);
  check_level_switch<3>(4u);
}

TEST_CASE("leaves found from a hint leaf equal those found from the roots") {
  for (unsigned seed : {1u, 2u}) check_leaf_hints<2>(seed);
  for (unsigned seed : {3u, 4u}) check_leaf_hints<3>(seed);
}

TEST_CASE("the free T-junction basis goes negative where the constrained one does not (Fig. 5b)") {
  // Lian et al.: N_c(0.5, 0.1) = 0.3375 - 0.3375 - 0.1375 < 0.
  CHECK(free_tjunction_Nc(0.5, 0.1) == doctest::Approx(-0.1375));
  // The same topology: level-0 cell (0, 0) with refined neighbours on its right and top, so
  // that the midpoints of its right and top edges are T-junctions.
  CellTree<2> tree(Vec<2>::Zero(), IVec<2>(2, 2), 2.0, 2);
  tree.refine(0, IVec<2>(1, 0));
  tree.refine(0, IVec<2>(0, 1));
  CHECK(home_level(tree, IVec<2>(2, 1)) == -1);  // b: constrained, no degree of freedom
  CHECK(home_level(tree, IVec<2>(1, 2)) == -1);  // d
  double free_min = 1.0, constrained_min = 1.0;
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; j <= 40; ++j) {
      const double x = -1 + i / 20.0, y = -1 + j / 20.0;  // cell coordinates in [-1, 1]^2
      free_min = std::min(free_min, free_tjunction_Nc(x, y));
      for (const auto& n : basis_at(tree, Vec<2>(Vec<2>(1 + x, 1 + y) * 0.999999)))
        constrained_min = std::min(constrained_min, n.weight);
    }
  CHECK(free_min < -0.1);
  CHECK(constrained_min >= 0.0);
}
