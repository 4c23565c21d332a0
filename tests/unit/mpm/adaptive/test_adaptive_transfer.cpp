// Transfers on the adaptive grid through ghost nodes, on random non-graded trees of 4 levels
// with particles of every type:
//  - P2G conserves mass and linear momentum to round-off across levels;
//  - APIC P2G and G2P conserve angular momentum (particle angular momentum includes the affine
//    part m_p (C_p D_p) : eps, Jiang et al. 2015), with D_p computed here from the weights;
//  - an affine velocity field passes P2G -> G2P exactly, C_p included;
//  - the internal forces of any stresses sum to zero, and their torque is zero for symmetric
//    stresses (sum_i grad w_ip = 0, sum_i x_i grad w_ip^T = I);
//  - a one-level tree reproduces the uniform grid's quadratic B-spline transfers;
//  - the memory of a grid whose finest level spans 2^13 cells per axis in 3D follows the
//    particles' blocks, not the domain;
//  - after a tree change, the grids and ghost tables equal those built from scratch;
//  - the ghosts' push (real nodes gather their links' sums in parallel) equals the serial
//    scatter, ghost by ghost, bit for bit; the embedded ghosts, and only they, keep the
//    moments R_k (a real node of another level has none);
//  - the ghost tables hold the nodes the stencils reach that are not real on their level, and
//    built afresh, no other node.
#include <mpm/adaptive/adaptive_transfer.h>
#include <mpm/core/particle_buckets.h>

#include <doctest/doctest.h>

#include "../core/random_particles.h"
#include "angular_momentum.h"
#include "random_tree.h"

#include <algorithm>
#include <map>
#include <random>
#include <set>
#include <utility>

using namespace mpm;
using namespace mpm::adaptive;
using mpm::test::cross;
using mpm::test::spin;

namespace {

// Particles of random types (levels) inside the domain of `tree`, with random v and C.
template <int dim>
Particles<dim> random_particles(const CellTree<dim>& tree, std::size_t n, unsigned seed,
                                std::vector<std::uint16_t>& type) {
  const double margin = 0.6 * tree.dx(0);
  const Vec<dim> lo = tree.origin().array() + margin;
  const Vec<dim> hi = (tree.origin() + tree.dx(0) * tree.base_cells().template cast<double>()).array() - margin;
  Particles<dim> P = test::random_cloud<dim>(n, lo, hi, seed);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> t(0, tree.finest());
  type.resize(n);
  for (auto& q : type) q = static_cast<std::uint16_t>(t(rng));
  return P;
}

// A random tree of 4 levels (test::random_tree) with random particles of every type, prepared.
template <int dim>
AdaptiveGrid<dim> prepared_grid(unsigned seed, Particles<dim>& P, std::vector<std::uint16_t>& type) {
  AdaptiveGrid<dim> grid(test::random_tree<dim>(seed, 4, 3));
  P = random_particles(grid.tree(), dim == 2 ? 400 : 150, seed, type);
  grid.prepare(P.x, type);
  return grid;
}

template <int dim>
std::size_t near_embedded_count(const AdaptiveGrid<dim>& grid) {
  std::size_t count = 0;
  for (int group = 0; group < grid.regular_groups(); ++group) count += grid.near_embedded(group).particle.size();
  return count;
}

// Calls fn(level, storage index) for every real node with mass.
template <int dim, class Fn>
void for_each_massive_node(const AdaptiveGrid<dim>& grid, Fn&& fn) {
  for (int n = 0; n < grid.levels(); ++n)
    for (std::size_t k = 0; k < grid.level(n).node_storage(); ++k)
      if (grid.level(n).mass[k] > 0.0) fn(n, k);
}

// D_p = sum_i w_ip (x_i - x_p)(x_i - x_p)^T from the weights on the real nodes.
template <int dim>
Mat<dim> inertia(const AdaptiveGrid<dim>& grid, std::size_t p, const Vec<dim>& x) {
  Mat<dim> D = Mat<dim>::Zero();
  for (const auto& rw : real_weights(grid, grid.transfer_level(p), grid.half_cells(p), x)) {
    const Vec<dim> r = grid.node_position(rw.level, rw.index) - x;
    D += rw.w * r * r.transpose();
  }
  return D;
}

template <int dim>
void check_conservation(unsigned seed) {
  std::vector<std::uint16_t> type;
  Particles<dim> P;
  AdaptiveGrid<dim> grid = prepared_grid(seed, P, type);
  int transitions = 0;
  for (std::size_t p = 0; p < P.size(); ++p) transitions += grid.transfer_level(p) != type[p];
  CHECK(transitions > 0);
  // Both adaptive paths are exercised: the general one, and the uniform loops with the
  // ghosts' APIC terms (the plain uniform loops: the one-level test below).
  CHECK(!grid.irregular().empty());
  CHECK(near_embedded_count(grid) > 0);
  // The uniform loops serve both regular groups: particles on their own level, and those one
  // level coarser whose box is a cell of the level (the quadratic B-spline), ghosts' terms too.
  std::size_t cell_boxes = 0, cell_boxes_near = 0;
  for (int n = 0; n < grid.levels(); ++n) {
    cell_boxes += grid.regular(AdaptiveGrid<dim>::groups_per_level * n + 1).particle.size();
    cell_boxes_near += grid.near_embedded(AdaptiveGrid<dim>::groups_per_level * n + 1).particle.size();
  }
  CHECK(cell_boxes > 0);
  CHECK(cell_boxes_near > 0);
  particles_to_grid(P, TransferScheme{}, grid);
  adaptive::momentum_to_velocity(grid, TransferScheme{});

  // Mass and linear momentum on the real nodes; ghosts hold nothing.
  double m_grid = 0.0;
  Vec<dim> p_grid = Vec<dim>::Zero(), p_particles = Vec<dim>::Zero();
  Eigen::Vector3d L_grid = Eigen::Vector3d::Zero(), L_particles = L_grid;
  for_each_massive_node(grid, [&](int n, std::size_t k) {
    CHECK(grid.ghosts(n).of_node(k) < 0);
    const double m = grid.level(n).mass[k];
    m_grid += m;
    p_grid += m * grid.level(n).velocity[k];
    L_grid += m * cross<dim>(grid.node_position(n, static_cast<Index>(k)), grid.level(n).velocity[k]);
  });
  for (std::size_t p = 0; p < P.size(); ++p) {
    p_particles += P.mass[p] * P.v[p];
    L_particles += P.mass[p] * (cross<dim>(P.x[p], P.v[p]) + spin<dim>(Mat<dim>(P.C[p] * inertia(grid, p, P.x[p]))));
  }
  CHECK(m_grid == doctest::Approx(P.total_mass()).epsilon(1e-13));
  CHECK((p_grid - p_particles).norm() < 1e-12 * P.total_mass());
  CHECK((L_grid - L_particles).norm() < 1e-12 * P.total_mass());

  // G2P (dt = 0) from random grid velocities: angular momentum of the grid equals that of
  // the particles, sum_p m_p (x_p x v_p + (C_p D_p) : eps).
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  L_grid.setZero();
  for_each_massive_node(grid, [&](int n, std::size_t k) {
    Vec<dim> v;
    for (int a = 0; a < dim; ++a) v[a] = u(rng);
    grid.level(n).velocity[k] = v;
    L_grid += grid.level(n).mass[k] * cross<dim>(grid.node_position(n, static_cast<Index>(k)), v);
  });
  pull_velocities(grid, TransferScheme{});
  grid_to_particles(P, TransferScheme{}, grid, 0.0);
  L_particles.setZero();
  for (std::size_t p = 0; p < P.size(); ++p)
    L_particles += P.mass[p] * (cross<dim>(P.x[p], P.v[p]) + spin<dim>(Mat<dim>(P.C[p] * inertia(grid, p, P.x[p]))));
  CHECK((L_grid - L_particles).norm() < 1e-12 * P.total_mass());
}

template <int dim>
void check_affine(unsigned seed) {
  AdaptiveGrid<dim> grid(test::random_tree<dim>(seed, 4, 3));
  std::vector<std::uint16_t> type;
  Particles<dim> P = random_particles(grid.tree(), dim == 2 ? 400 : 150, seed + 7, type);
  const Vec<dim> a = Vec<dim>::LinSpaced(0.3, -0.2);
  Mat<dim> B;
  for (int i = 0; i < dim * dim; ++i) B.data()[i] = 0.1 * (i + 1) - 0.35;
  for (std::size_t p = 0; p < P.size(); ++p) {
    P.v[p] = a + B * P.x[p];
    P.C[p] = B;
  }
  grid.prepare(P.x, type);
  CHECK(near_embedded_count(grid) > 0);
  particles_to_grid(P, TransferScheme{}, grid);
  adaptive::momentum_to_velocity(grid, TransferScheme{});
  double worst_grid = 0.0;
  for_each_massive_node(grid, [&](int n, std::size_t k) {
    const Vec<dim> x = grid.node_position(n, static_cast<Index>(k));
    worst_grid = std::max(worst_grid, (grid.level(n).velocity[k] - (a + B * x)).norm());
  });
  CHECK(worst_grid < 1e-12);
  for (auto& v : P.v) v.setZero();
  for (auto& C : P.C) C.setZero();
  pull_velocities(grid, TransferScheme{});
  grid_to_particles(P, TransferScheme{}, grid, 0.0);
  double worst_v = 0.0, worst_C = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    worst_v = std::max(worst_v, (P.v[p] - (a + B * P.x[p])).norm());
    worst_C = std::max(worst_C, (P.C[p] - B).norm());
  }
  CHECK(worst_v < 1e-12);
  CHECK(worst_C < 1e-10);
}

template <int dim>
void check_forces(unsigned seed) {
  AdaptiveGrid<dim> grid(test::random_tree<dim>(seed, 4, 3));
  std::vector<std::uint16_t> type;
  Particles<dim> P = random_particles(grid.tree(), dim == 2 ? 300 : 100, seed + 11, type);
  grid.prepare(P.x, type);
  std::vector<Mat<dim>> S(P.size());
  for (std::size_t p = 0; p < P.size(); ++p) S[p] = P.C[p] + P.C[p].transpose();  // symmetric
  stress_to_grid_forces(S, P, grid);
  Vec<dim> total = Vec<dim>::Zero();
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();
  double scale = 0.0;
  for (int n = 0; n < grid.levels(); ++n)
    for (std::size_t k = 0; k < grid.level(n).node_storage(); ++k) {
      const Vec<dim>& f = grid.level(n).force[k];
      if (grid.ghosts(n).of_node(k) >= 0) CHECK(f.norm() == 0.0);
      total += f;
      torque += cross<dim>(grid.node_position(n, static_cast<Index>(k)), f);
      scale = std::max(scale, f.norm());
    }
  REQUIRE(scale > 0.0);
  CHECK(total.norm() < 1e-12 * scale);
  CHECK(torque.norm() < 1e-12 * scale);

  // The fused scatter (p2g with the forces, the explicit step's) gives the forces of the pass
  // above and the mass and momentum of a plain p2g, bit for bit.
  std::vector<std::vector<Vec<dim>>> force(grid.levels());
  for (int n = 0; n < grid.levels(); ++n) force[n] = grid.level(n).force;
  particles_to_grid(P, TransferScheme{}, grid);
  std::vector<std::vector<double>> mass(grid.levels());
  std::vector<std::vector<Vec<dim>>> momentum(grid.levels());
  for (int n = 0; n < grid.levels(); ++n) {
    mass[n] = grid.level(n).mass;
    momentum[n] = grid.level(n).velocity;
    std::fill(grid.level(n).force.begin(), grid.level(n).force.end(), Vec<dim>::Constant(1.0));
  }
  particles_to_grid(P, TransferScheme{}, grid, &S);
  for (int n = 0; n < grid.levels(); ++n) {
    CHECK(grid.level(n).force == force[n]);
    CHECK(grid.level(n).mass == mass[n]);
    CHECK(grid.level(n).velocity == momentum[n]);
  }

  // With the forces as an impulse (the explicit APIC step's): the momentum of every real node
  // and ghost is momentum + dt force to round-off, irregular particles and pushed ghosts
  // included, and no level keeps a force channel.
  const double dt = 0.7;
  particles_to_grid(P, TransferScheme{}, grid, &S, dt);
  double worst = 0.0, largest = 0.0, impulse = 0.0;
  for (int n = 0; n < grid.levels(); ++n) {
    CHECK(grid.level(n).force.empty());
    CHECK(grid.level(n).mass == mass[n]);
    for (std::size_t k = 0; k < grid.level(n).node_storage(); ++k) {
      const Vec<dim> expected = momentum[n][k] + dt * force[n][k];
      worst = std::max(worst, (grid.level(n).velocity[k] - expected).norm());
      largest = std::max(largest, expected.norm());
      impulse = std::max(impulse, dt * force[n][k].norm());
    }
  }
  REQUIRE(impulse > 0.1 * largest);
  CHECK(worst < 1e-13 * largest);
}

// prepare() stores scattered particles in transfer order (each level's buckets, then the
// irregular particles) and renumbers its tables: the transfers give bit for bit what they give
// on the particles left in place.
template <int dim>
void check_transfer_order(unsigned seed) {
  const CellTree<dim> tree = test::random_tree<dim>(seed, 4, 3);
  std::vector<std::uint16_t> type;
  // More particles than the loops run serially below (bucket_loops.h): the parallel paths count.
  Particles<dim> A = random_particles(tree, 6000, seed + 5, type);
  Particles<dim> M = A;
  std::vector<std::uint16_t> type_M = type;
  AdaptiveGrid<dim> in_place(tree), moving(tree);
  CHECK_FALSE(in_place.prepare(A.x, type));
  // The irregular particles scatter a colour's groups in parallel: no node in two of them.
  const auto& groups = in_place.irregular_groups();
  std::size_t colored = 0;
  for (const std::vector<int>& same_color : groups.by_color) {
    std::map<std::pair<int, Index>, int> owner;
    for (const int g : same_color)
      for (std::uint32_t e = groups.begin[g]; e < groups.begin[g + 1]; ++e) {
        const std::uint32_t p = in_place.irregular()[e];
        const int n = in_place.transfer_level(p);
        ++colored;
        in_place.for_each_weight(n, in_place.half_cells(p), A.x[p],
                                 [&](Index k, double, const Vec<dim>&, const Vec<dim>&) {
                                   const auto [it, inserted] = owner.try_emplace({n, k}, g);
                                   CHECK((inserted || it->second == g));
                                 });
      }
  }
  CHECK(colored == in_place.irregular().size());
  REQUIRE(in_place.irregular().size() > 2048);  // the parallel path (bucket_loops.h)
  std::vector<std::uint32_t> order;
  const auto move = [&](const std::vector<std::uint32_t>& o) {
    order = o;
    M.permute(o);
    const std::vector<std::uint16_t> before = type_M;
    for (std::size_t i = 0; i < o.size(); ++i) type_M[i] = before[o[i]];
  };
  REQUIRE(moving.prepare(M.x, type_M, "sort", move));
  REQUIRE(order.size() == A.size());
  REQUIRE(near_embedded_count(moving) > 0);
  std::uint32_t next = 0;  // storage order is transfer order
  for (int group = 0; group < moving.regular_groups(); ++group)
    for (const std::uint32_t p : moving.regular(group).particle) CHECK(p == next++);
  for (const std::uint32_t p : moving.irregular()) CHECK(p == next++);
  for (std::size_t i = 0; i < order.size(); ++i) {
    CHECK(moving.transfer_level(i) == in_place.transfer_level(order[i]));
    CHECK(moving.half_cells(i) == in_place.half_cells(order[i]));
  }

  for (auto* run : {&A, &M}) {
    AdaptiveGrid<dim>& grid = run == &A ? in_place : moving;
    particles_to_grid(*run, TransferScheme{}, grid);
    adaptive::momentum_to_velocity(grid, TransferScheme{});
    for (int n = 0; n < grid.levels(); ++n)  // a quadratic velocity field: the ghosts' APIC terms count
      for (std::size_t k = 0; k < grid.level(n).node_storage(); ++k)
        if (grid.level(n).mass[k] > 0.0)
          grid.level(n).velocity[k] += grid.node_position(n, static_cast<Index>(k)).array().square().matrix();
    pull_velocities(grid, TransferScheme{});
    grid_to_particles(*run, TransferScheme{}, grid, 1e-3);
  }
  for (int n = 0; n < tree.levels(); ++n) CHECK(moving.level(n).mass == in_place.level(n).mass);
  for (std::size_t i = 0; i < order.size(); ++i) {
    CHECK(M.v[i] == A.v[order[i]]);
    CHECK(M.C[i] == A.C[order[i]]);
    CHECK(M.x[i] == A.x[order[i]]);
  }
  CHECK_FALSE(moving.prepare(M.x, type_M, "sort", move));  // in order now
}

// G2P with `then` (the explicit step's return map): every particle is handed over exactly once,
// with its v, x and F final, and what `then` does to F stays; C, completed afterwards for the
// particles near embedded ghosts, is that of G2P without it. Bit for bit.
template <int dim>
void check_g2p_then(unsigned seed) {
  const CellTree<dim> tree = test::random_tree<dim>(seed, 4, 3);
  std::vector<std::uint16_t> type;
  Particles<dim> P = random_particles(tree, 6000, seed + 3, type);  // the parallel paths
  AdaptiveGrid<dim> grid(tree);
  grid.prepare(P.x, type);
  REQUIRE(near_embedded_count(grid) > 0);
  REQUIRE(!grid.irregular().empty());
  particles_to_grid(P, TransferScheme{}, grid);
  adaptive::momentum_to_velocity(grid, TransferScheme{});
  for (int n = 0; n < grid.levels(); ++n)
    for (std::size_t k = 0; k < grid.level(n).node_storage(); ++k)
      if (grid.level(n).mass[k] > 0.0)
        grid.level(n).velocity[k] += grid.node_position(n, static_cast<Index>(k)).array().square().matrix();
  pull_velocities(grid, TransferScheme{});

  Particles<dim> Q = P;
  std::vector<Mat<dim>> F_P(P.size()), F_Q;
  for (std::size_t p = 0; p < P.size(); ++p) F_P[p] = Mat<dim>::Identity() + 0.01 * P.C[p];
  F_Q = F_P;
  grid_to_particles(Q, TransferScheme{}, grid, 1e-3, &F_Q);
  std::vector<int> visits(P.size(), 0);
  std::vector<Vec<dim>> v_seen(P.size()), x_seen(P.size());
  std::vector<Mat<dim>> F_seen(P.size());
  const ParticleGroupUpdate then = [&](const std::uint32_t* first, const std::uint32_t* last) {
    for (const std::uint32_t* p = first; p != last; ++p) {
      ++visits[*p];
      v_seen[*p] = P.v[*p];
      x_seen[*p] = P.x[*p];
      F_seen[*p] = F_P[*p];
      F_P[*p] *= 2.0;
    }
  };
  grid_to_particles(P, TransferScheme{}, grid, 1e-3, &F_P, &then);
  for (std::size_t p = 0; p < P.size(); ++p) {
    CHECK(visits[p] == 1);
    CHECK(v_seen[p] == Q.v[p]);
    CHECK(x_seen[p] == Q.x[p]);
    CHECK(F_seen[p] == F_Q[p]);
    CHECK(F_P[p] == 2.0 * F_Q[p]);
    CHECK(P.C[p] == Q.C[p]);
  }
}

// One level, boxes of one cell: the adaptive transfer is the uniform quadratic B-spline transfer.
template <int dim>
void check_uniform_limit() {
  const CellTree<dim> tree(Vec<dim>::Zero(), IVec<dim>::Constant(8), 0.125, 1);
  AdaptiveGrid<dim> grid(tree, 1);  // one particle per axis per cell: boxes of dx
  Particles<dim> P = test::random_cloud<dim>(300, Vec<dim>::Constant(0.2), Vec<dim>::Constant(0.8), 3);
  Particles<dim> Q = P;
  grid.prepare(P.x, std::vector<std::uint16_t>(P.size(), 0));
  particles_to_grid(P, TransferScheme{}, grid);
  adaptive::momentum_to_velocity(grid, TransferScheme{});

  SparseGrid<dim> uniform(Vec<dim>::Zero(), Vec<dim>::Constant(1.0), 0.125);
  ParticleBuckets<dim> buckets;
  sort_into_buckets(Q, QuadraticBSpline{}, uniform, buckets);
  mpm::particles_to_grid(Q, buckets, QuadraticBSpline{}, TransferScheme{}, uniform);
  momentum_to_velocity(uniform, TransferScheme{});
  double worst = 0.0;
  for (std::size_t k = 0; k < uniform.node_storage(); ++k) {
    const Index j = grid.level(0).node_index(uniform.node_coord(k));
    if (j < 0) {
      CHECK(uniform.mass[k] == 0.0);
      continue;
    }
    worst = std::max(worst, std::abs(grid.level(0).mass[j] - uniform.mass[k]));
    worst = std::max(worst, (grid.level(0).velocity[j] - uniform.velocity[k]).norm());
  }
  CHECK(worst < 1e-13);
  pull_velocities(grid, TransferScheme{});
  grid_to_particles(P, TransferScheme{}, grid, 0.01);
  mpm::grid_to_particles(Q, buckets, QuadraticBSpline{}, TransferScheme{}, uniform, 0.01);
  for (std::size_t p = 0; p < P.size(); ++p) {
    const std::size_t q = static_cast<std::size_t>(std::find(Q.mass.begin(), Q.mass.end(), P.mass[p]) - Q.mass.begin());
    REQUIRE(q < Q.size());
    CHECK((P.v[p] - Q.v[q]).norm() < 1e-13);
    CHECK((P.C[p] - Q.C[q]).norm() < 1e-10);
    CHECK((P.x[p] - Q.x[q]).norm() < 1e-15);
  }
}

// Random values on every node and random G_k; push_momentum() and push() against the serial
// scatter written out here from the ghost tables: equal bit for bit (each real node adds its
// links in the scatter's order).
template <int dim>
void check_push(unsigned seed) {
  std::vector<std::uint16_t> type;
  Particles<dim> P;
  AdaptiveGrid<dim> grid = prepared_grid(seed, P, type);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int L = grid.levels();
  std::vector<std::vector<Mat<dim>>> affine(L);
  std::size_t links = 0;
  for (int n = 0; n < L; ++n) {
    SparseGrid<dim>& g = grid.level(n);
    g.force.resize(g.node_storage());
    for (std::size_t k = 0; k < g.node_storage(); ++k) {
      g.mass[k] = 2.0 + u(rng);
      for (int a = 0; a < dim; ++a) {
        g.velocity[k][a] = u(rng);
        g.force[k][a] = u(rng);
      }
    }
    affine[n].resize(grid.ghosts(n).node.size());
    for (Mat<dim>& G : affine[n])
      for (int i = 0; i < dim * dim; ++i) G.data()[i] = u(rng);
    links += grid.ghosts(n).link.size();
  }
  REQUIRE(links > 0);
  std::vector<std::vector<double>> mass(L);
  std::vector<std::vector<Vec<dim>>> velocity(L), force(L);
  for (int n = 0; n < L; ++n) {
    mass[n] = grid.level(n).mass;
    velocity[n] = grid.level(n).velocity;
    force[n] = grid.level(n).force;
  }
  for (int n = 0; n < L; ++n) {
    const auto& g = grid.ghosts(n);
    int next_moment = 0;  // the embedded ghosts' rows of spread, in ghost order
    for (std::size_t j = 0; j < g.node.size(); ++j) {
      const std::size_t k = static_cast<std::size_t>(g.node[j]);
      const Vec<dim> xk = grid.node_position(n, g.node[j]);
      // A ghost has moments iff it is not a real node of another level (one link of weight 1
      // at its own position), and they are its links' second moment R_k.
      Mat<dim> R = Mat<dim>::Zero();
      for (std::uint32_t l = g.begin[j]; l < g.begin[j + 1]; ++l) {
        const Vec<dim> r = grid.link_offset(g.link[l], xk);
        R += g.link[l].weight * r * r.transpose();
      }
      const bool collocated = g.begin[j + 1] - g.begin[j] == 1 && g.link[g.begin[j]].weight == 1.0 &&
                              grid.link_offset(g.link[g.begin[j]], xk) == Vec<dim>::Zero();
      if (collocated) {
        CHECK(g.moment[j] == -1);
      } else {
        REQUIRE(g.moment[j] == next_moment++);
        const Mat<dim> stored = g.spread_of(g.moment[j]);  // symmetric by construction
        CHECK((stored - R).norm() <= 1e-15 * R.norm());
      }
      for (std::uint32_t l = g.begin[j]; l < g.begin[j + 1]; ++l) {
        const GhostLink<dim>& link = g.link[l];
        const std::size_t i = static_cast<std::size_t>(link.index);
        mass[link.level][i] += link.weight * mass[n][k];
        velocity[link.level][i] += link.weight * (velocity[n][k] + affine[n][j] * grid.link_offset(link, xk));
        force[link.level][i] += link.weight * force[n][k];
      }
      mass[n][k] = 0.0;
      velocity[n][k].setZero();
      force[n][k].setZero();
    }
  }
  grid.push_momentum(affine);
  std::vector<std::vector<Vec<dim>>*> forces;
  for (int n = 0; n < L; ++n) forces.push_back(&grid.level(n).force);
  grid.push(forces);
  for (int n = 0; n < L; ++n) {
    CHECK(grid.level(n).mass == mass[n]);
    CHECK(grid.level(n).velocity == velocity[n]);
    CHECK(grid.level(n).force == force[n]);
  }
}

// The nodes of level n that the particles' stencils reach: the 3^dim stencils of the regular
// particles (the uniform loops write all of them) and the general stencils of the others.
template <int dim>
std::set<Index> reached_nodes(const AdaptiveGrid<dim>& grid, const Particles<dim>& P, int n) {
  std::set<Index> reached;
  const SparseGrid<dim>& g = grid.level(n);
  const auto add_box = [&](const IVec<dim>& first, const IVec<dim>& count) {
    for_each_in_box<dim>(first, IVec<dim>(first + count - IVec<dim>::Ones()),
                         [&](const IVec<dim>& node) { reached.insert(g.node_index(node)); });
  };
  for (int group = AdaptiveGrid<dim>::groups_per_level * n; group < AdaptiveGrid<dim>::groups_per_level * (n + 1);
       ++group)
    for (const std::uint32_t p : grid.regular(group).particle)
      add_box(grid.uniform_base(n, P.x[p]), IVec<dim>::Constant(3));
  for (const std::uint32_t p : grid.irregular()) {
    if (grid.transfer_level(p) != n) continue;
    GimpAxis axis[dim];
    grid.axis_weights(n, grid.half_cells(p), P.x[p], axis);
    IVec<dim> first, count;
    for (int a = 0; a < dim; ++a) {
      first[a] = axis[a].base;
      count[a] = axis[a].count;
    }
    add_box(first, count);
  }
  return reached;
}

// Every node a stencil reaches is either real on its level or a ghost with a table entry;
// built afresh, the tables hold no other node; after the particles move, the tables kept or
// rebuilt still hold every node reached.
template <int dim>
void check_ghost_tables(unsigned seed) {
  std::vector<std::uint16_t> type;
  Particles<dim> P;
  AdaptiveGrid<dim> grid = prepared_grid(seed, P, type);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (int round = 0; round < 3; ++round) {
    std::size_t ghosts = 0, unreached = 0;
    for (int n = 0; n < grid.levels(); ++n) {
      const std::set<Index> reached = reached_nodes(grid, P, n);
      for (const Index k : reached) {
        const IVec<dim> point = grid.level(n).node_coord(static_cast<std::size_t>(k)) * grid.tree().scale(n);
        const bool real = home_level(grid.tree(), point) == n;
        CHECK(real != (grid.ghosts(n).of_node(k) >= 0));
      }
      for (const Index k : grid.ghosts(n).node) unreached += !reached.count(k);
      // Every ghost is found at its node (of_node() counts a block's ghosts before it).
      const auto& tables = grid.ghosts(n);
      int misplaced = 0;
      for (std::size_t j = 0; j < tables.node.size(); ++j) misplaced += tables.of_node(tables.node[j]) != int(j);
      CHECK(misplaced == 0);
      ghosts += grid.ghosts(n).node.size();
    }
    CHECK(ghosts > 0);
    if (round == 0) CHECK(unreached == 0);
    // The tables kept or rebuilt from kept and recomputed statuses link every ghost as a grid
    // prepared from scratch does.
    AdaptiveGrid<dim> fresh(grid.tree());
    fresh.prepare(P.x, type);
    for (int n = 0; n < grid.levels(); ++n) {
      const auto& a = grid.ghosts(n);
      const auto& b = fresh.ghosts(n);
      for (std::size_t j = 0; j < b.node.size(); ++j) {
        const Vec<dim> x = fresh.node_position(n, b.node[j]);
        const int i =
            a.of_node(grid.level(n).node_index(fresh.level(n).node_coord(static_cast<std::size_t>(b.node[j]))));
        REQUIRE(i >= 0);
        REQUIRE(a.begin[i + 1] - a.begin[i] == b.begin[j + 1] - b.begin[j]);
        for (std::uint32_t l = 0; l < b.begin[j + 1] - b.begin[j]; ++l) {
          const GhostLink<dim>& la = a.link[a.begin[i] + l];
          const GhostLink<dim>& lb = b.link[b.begin[j] + l];
          CHECK(la.level == lb.level);
          CHECK(la.weight == lb.weight);
          CHECK(grid.link_offset(la, x) == fresh.link_offset(lb, x));
        }
      }
    }
    // A small move (a fraction of the finest cell): most steps keep the tables.
    for (std::size_t p = 0; p < P.size(); ++p)
      for (int a = 0; a < dim; ++a) P.x[p][a] += u(rng) * grid.tree().dx(grid.tree().finest());
    grid.prepare(P.x, type);
  }
}

}  // namespace

TEST_CASE("the ghost tables hold exactly the nodes the stencils reach that are not real on their level") {
  for (unsigned seed : {1u, 2u, 3u}) check_ghost_tables<2>(seed);
  for (unsigned seed : {4u, 5u}) check_ghost_tables<3>(seed);
}

TEST_CASE(
    "the ghosts' push gathers in parallel what the serial scatter adds, bit for bit; only embedded ghosts keep "
    "moments") {
  for (unsigned seed : {1u, 2u}) check_push<2>(seed);
  check_push<3>(4u);
}

TEST_CASE("adaptive P2G/G2P conserve mass, linear and angular momentum across levels") {
  for (unsigned seed : {1u, 2u, 3u}) check_conservation<2>(seed);
  for (unsigned seed : {4u, 5u}) check_conservation<3>(seed);
}

TEST_CASE("adaptive APIC reproduces an affine velocity field through P2G -> G2P") {
  for (unsigned seed : {1u, 2u}) check_affine<2>(seed);
  check_affine<3>(4u);
}

TEST_CASE("adaptive prepare stores scattered particles in transfer order without changing the transfers") {
  check_transfer_order<2>(17);
  check_transfer_order<3>(18);
}

TEST_CASE("adaptive G2P hands each particle to `then` once, with its v, x and F final") {
  check_g2p_then<2>(21);
  check_g2p_then<3>(22);
}

TEST_CASE(
    "adaptive internal forces sum to zero with zero torque for symmetric stresses, also from the fused p2g and as an "
    "impulse") {
  for (unsigned seed : {1u, 2u}) check_forces<2>(seed);
  check_forces<3>(4u);
}

TEST_CASE("a one-level adaptive grid reproduces the uniform quadratic transfers") {
  check_uniform_limit<2>();
  check_uniform_limit<3>();
}

TEST_CASE("count_refinements counts the cells refine_where refines, without refining, and stops past its cap") {
  // A disk refined to level 3 inside a box refined to level 2, over 6 x 4 level-0 cells.
  const auto target = [](const Vec<2>& lo, const Vec<2>& hi) {
    const Vec<2> nearest = Vec<2>(0.7, 0.5).cwiseMax(lo).cwiseMin(hi);
    if ((nearest - Vec<2>(0.7, 0.5)).norm() < 0.2) return 3;
    return (lo.array() < 1.2).all() && (hi.array() > 0.3).all() ? 2 : 0;
  };
  const CellTree<2> unrefined(Vec<2>::Zero(), IVec<2>(6, 4), 0.25, 4);
  const double counted = unrefined.count_refinements(target, 1e18);
  CellTree<2> tree = unrefined;
  tree.refine_where(target);
  std::size_t leaves = 0;
  tree.for_each_leaf([&](int, const IVec<2>&) { ++leaves; });
  CHECK(counted > 50.0);
  CHECK(counted == static_cast<double>(leaves - 24) / 3.0);  // each refinement adds 3 leaves
  CHECK(unrefined.count_refinements(target, 5.0) == 6.0);
  CHECK(unrefined == CellTree<2>(Vec<2>::Zero(), IVec<2>(6, 4), 0.25, 4));
}

TEST_CASE("a 3D grid spanning 2^13 finest cells per axis holds memory for the particles' blocks only") {
  // 4 levels over 1024^3 coarse cells: the finest level has 8192 = 2^13 cells per axis. A
  // dense block table alone would hold (8192 / 4)^3 * 4 bytes = 34 GB on that level.
  CellTree<3> tree(Vec<3>::Zero(), IVec<3>::Constant(1024), 1.0 / 1024, 4);
  const Vec<3> lo = Vec<3>::Constant(0.5), hi = Vec<3>::Constant(0.5 + 8.0 / 1024);
  tree.refine_where(
      [&](const Vec<3>& a, const Vec<3>& b) {
        return (a.array() < hi.array()).all() && (b.array() > lo.array()).all() ? 3 : 0;
      },
      lo, hi);
  AdaptiveGrid<3> grid(tree);
  Particles<3> P = test::random_cloud<3>(2000, lo, hi, 9);
  grid.prepare(P.x, std::vector<std::uint16_t>(P.size(), 3));
  std::size_t blocks = 0;
  for (int n = 0; n < grid.levels(); ++n) blocks += static_cast<std::size_t>(grid.level(n).block_count());
  const std::size_t node_bytes = SparseGrid<3>::nodes_per_block * (sizeof(double) + sizeof(Vec<3>) + sizeof(int));
  MESSAGE("allocated blocks: ", blocks, ", memory held: ", grid.memory_bytes(), " bytes");
  CHECK(blocks > 0);
  CHECK(blocks <= 5832);  // the particles span 64 finest cells per axis: at most (64 / 4 + 2)^3 blocks
  // Per allocated block: its nodes' channels, ghost tables and cached node statuses (a bounded
  // multiple of a block's node channels), and a fixed share of tables. A domain-sized table
  // would be 34 GB.
  CHECK(grid.memory_bytes() < blocks * 10 * node_bytes + (1u << 20));
  particles_to_grid(P, TransferScheme{}, grid);
  adaptive::momentum_to_velocity(grid, TransferScheme{});
  double m = 0.0;
  for (int n = 0; n < grid.levels(); ++n)
    for (double mi : grid.level(n).mass) m += mi;
  CHECK(m == doctest::Approx(P.total_mass()).epsilon(1e-13));
}

namespace {
// The ghost tables of level n as (ghost node, links (level, node, weight)) with the lattice
// coordinates taken relative to `shift` level-0 cells along axis 0.
using Coord = std::array<int, 3>;
using GhostSet = std::set<std::tuple<Coord, std::vector<std::tuple<int, Coord, double>>>>;
GhostSet relative_ghosts(const AdaptiveGrid<3>& grid, int n, int shift) {
  const auto relative = [&](int level, Index k) {
    const IVec<3> c = grid.level(level).node_coord(static_cast<std::size_t>(k));
    return Coord{c[0] - (shift << level), c[1], c[2]};
  };
  const auto& g = grid.ghosts(n);
  GhostSet out;
  for (std::size_t j = 0; j < g.node.size(); ++j) {
    std::vector<std::tuple<int, Coord, double>> links;
    for (std::uint32_t l = g.begin[j]; l < g.begin[j + 1]; ++l)
      links.emplace_back(g.link[l].level, relative(g.link[l].level, g.link[l].index), g.link[l].weight);
    out.emplace(relative(n, g.node[j]), links);
  }
  return out;
}

// The same cloud of 300 particles (finest type where x < 4, coarsest beyond) and refinement
// (finest level where x < 3.5 and y < 3) at each offset along axis 0 of a tree `cells` level-0
// cells long (dx0 = 1), prepared.
AdaptiveGrid<3> shifted_clouds(int cells, const std::vector<int>& offsets) {
  const Particles<3> P = test::random_cloud<3>(300, Vec<3>(1.2, 1.2, 1.2), Vec<3>(6.8, 2.8, 2.8), 5);
  CellTree<3> tree(Vec<3>::Zero(), IVec<3>(cells, 4, 4), 1.0, 3);
  std::vector<Vec<3>> x;
  std::vector<std::uint16_t> type;
  for (const int offset : offsets) {
    tree.refine_where([&](const Vec<3>& a, const Vec<3>&) { return a[0] < offset + 3.5 && a[1] < 3.0 ? 2 : 0; },
                      Vec<3>(offset, 0, 0), Vec<3>(offset + 4.0, 4, 4));
    for (const Vec<3>& xp : P.x) {
      x.push_back(xp + Vec<3>(offset, 0, 0));
      type.push_back(xp[0] < 4.0 ? 2 : 0);
    }
  }
  AdaptiveGrid<3> grid(tree);
  grid.prepare(x, type);
  return grid;
}
}  // namespace

TEST_CASE("the widest tree's far end has the ghost tables of its near end (packed node statuses)") {
  // The node statuses pack a lattice point in 20 bits per axis in 3D, as many as a tree
  // addresses: a tree of 2^18 - 1 level-0 cells over 3 levels spans 2^20 - 4 finest cells.
  // The same refinement and particles at its far end and at the origin of a small tree give
  // the same ghost tables, up to the shift.
  const int far = (1 << 18) - 1, near = 8, shift = far - near;
  const AdaptiveGrid<3> small = shifted_clouds(near, {0}), widest = shifted_clouds(far, {shift});
  std::size_t ghosts = 0;
  for (int n = 0; n < 3; ++n) {
    ghosts += small.ghosts(n).node.size();
    CHECK(relative_ghosts(widest, n, shift) == relative_ghosts(small, n, 0));
  }
  CHECK(ghosts > 50);
  CHECK_THROWS_AS(CellTree<3>(Vec<3>::Zero(), IVec<3>(1 << 18, 4, 4), 1.0, 3), Error);  // 2^20: one too many
}

TEST_CASE("two clouds far apart get the blocks and ghosts of each alone (block lists of a wide bounding box)") {
  // prepare() sorts a level's block list through a bitmap over the blocks' bounding box, or by
  // comparison when the box is much larger than the list: here the same cloud and refinement
  // near the origin and 4 000 level-0 cells away, against the cloud alone.
  const int shift = 4000;  // a multiple of the block size: blocks shift whole
  const AdaptiveGrid<3> alone = shifted_clouds(8, {0}), both = shifted_clouds(shift + 8, {0, shift});
  for (int n = 0; n < 3; ++n) {
    const SparseGrid<3>& g = alone.level(n);
    std::vector<BlockKey> expected = g.active_blocks();
    for (const BlockKey key : g.active_blocks()) {
      IVec<3> c = g.block_coord(key) * SparseGrid<3>::block_size;
      c[0] += shift << n;  // in level-n nodes
      expected.push_back(both.level(n).block_id(c));
    }
    std::sort(expected.begin(), expected.end());
    CHECK(both.level(n).active_blocks() == expected);
    // Each cloud's ghosts, with their links, are the lone cloud's: seen from either origin,
    // the lone cloud's set is part of both's, which holds twice as many.
    const GhostSet one = relative_ghosts(alone, n, 0);
    for (const int origin : {0, shift}) {
      const GhostSet seen = relative_ghosts(both, n, origin);
      CHECK(std::includes(seen.begin(), seen.end(), one.begin(), one.end()));
    }
    CHECK(both.ghosts(n).node.size() == 2 * alone.ghosts(n).node.size());
  }
  CHECK(alone.ghosts(2).node.size() > 20);
}

namespace {
// prepare() after a tree change keeps the node statuses the change cannot reach: its grids and
// ghost tables equal those of a grid prepared on the new tree from scratch.
template <int dim>
void check_tree_change(unsigned seed) {
  const CellTree<dim> coarse = test::random_tree<dim>(seed, 4, 4);
  CellTree<dim> fine = coarse;  // coarse with a few more cells refined
  std::mt19937 rng(seed);
  int refined = 0;
  std::vector<std::pair<int, IVec<dim>>> leaves;
  coarse.for_each_leaf([&](int level, const IVec<dim>& cell) { leaves.emplace_back(level, cell); });
  for (const auto& [level, cell] : leaves)
    if (level < fine.finest() && rng() % 6 == 0 && ++refined) fine.refine(level, cell);
  REQUIRE(refined > 0);
  std::vector<std::uint16_t> type;
  const Particles<dim> P = random_particles(coarse, dim == 2 ? 400 : 150, seed, type);

  AdaptiveGrid<dim> changing(coarse);
  changing.prepare(P.x, type);
  for (const CellTree<dim>* tree :
       {&std::as_const(fine), &coarse, &std::as_const(fine)}) {  // refinement added, removed, added
    changing.tree() = *tree;
    changing.prepare(P.x, type);
    AdaptiveGrid<dim> fresh(*tree);
    fresh.prepare(P.x, type);
    CHECK(changing.irregular() == fresh.irregular());
    for (int group = 0; group < fresh.regular_groups(); ++group)
      CHECK(changing.near_embedded(group).particle == fresh.near_embedded(group).particle);
    for (int n = 0; n < fresh.levels(); ++n) {
      CHECK(changing.level(n).active_blocks() == fresh.level(n).active_blocks());
      const auto& a = changing.ghosts(n);
      const auto& b = fresh.ghosts(n);
      REQUIRE(a.node == b.node);
      REQUIRE(a.begin == b.begin);
      REQUIRE(a.link.size() == b.link.size());
      for (std::size_t l = 0; l < a.link.size(); ++l) {
        CHECK(a.link[l].level == b.link[l].level);
        CHECK(a.link[l].index == b.link[l].index);
        CHECK(a.link[l].weight == b.link[l].weight);
      }
      REQUIRE(a.moment == b.moment);
      REQUIRE(a.spread.size() == b.spread.size());
      for (std::size_t j = 0; j < a.spread.size(); ++j) CHECK(a.spread[j] == b.spread[j]);
    }
  }
}
}  // namespace

TEST_CASE("after a tree change the adaptive grid keeps only the node statuses the change cannot reach") {
  for (unsigned seed : {1u, 2u, 3u, 5u, 6u, 7u}) check_tree_change<2>(seed);
  for (unsigned seed : {4u, 8u}) check_tree_change<3>(seed);
}
