// P2G conserves mass and linear momentum to round-off; APIC P2G conserves angular momentum
// (particle angular momentum includes the affine part, Jiang et al. 2015 sec. 5.3); an affine
// velocity field survives P2G -> G2P exactly, C_p included; the sparse grid allocates only
// the blocks near particles; grid_to_scalar reads linear node fields exactly and is the adjoint
// of scalar_to_grid.
#include <mpm/core/error.h>
#include <mpm/core/transfer.h>

#include <doctest/doctest.h>
#include <Eigen/Geometry>

#include "random_particles.h"

#include <random>

using namespace mpm;

namespace {
using test::random_cloud;

template <int dim>
double cross(const Vec<dim>& a, const Vec<dim>& b, int axis) {
  if constexpr (dim == 2)
    return a[0] * b[1] - a[1] * b[0];
  else
    return a.cross(b)[axis];
}

// APIC inertia D_p = sum_i w_ip (x_i - x_p)(x_i - x_p)^T computed by brute force.
template <int dim>
Mat<dim> inertia(const Kernel& kernel, const SparseGrid<dim>& g, const Vec<dim>& x) {
  Mat<dim> D = Mat<dim>::Zero();
  std::visit(
      [&](const auto& k) {
        int base[dim];
        double w[dim][4], dw[dim][4];
        for (int a = 0; a < dim; ++a) k((x[a] - g.origin()[a]) / g.dx(), base[a], w[a], dw[a]);
        for (int a = 0; a < dim; ++a) {
          double s = 0;
          for (int i = 0; i < k.support; ++i) {
            const double r = (g.origin()[a] + (base[a] + i) * g.dx()) - x[a];
            s += w[a][i] * r * r;
          }
          D(a, a) = s;  // off-diagonals vanish by linear reproduction
        }
      },
      kernel);
  return D;
}

template <int dim>
void check_conservation(const Kernel& kernel) {
  CAPTURE(dim);
  CAPTURE(kernel_name(kernel));
  const Vec<dim> lo = Vec<dim>::Zero(), hi = Vec<dim>::Ones();
  SparseGrid<dim> grid(lo, hi, 1.0 / 32);
  Particles<dim> P = random_cloud<dim>(3000, Vec<dim>::Constant(0.2), Vec<dim>::Constant(0.8), 7);
  ParticleBuckets<dim> buckets;
  sort_into_buckets(P, kernel, grid, buckets);
  particles_to_grid(P, buckets, kernel, TransferScheme{}, grid);

  double mp = 0, mg = 0;
  Vec<dim> pp = Vec<dim>::Zero(), pg = Vec<dim>::Zero();
  constexpr int naxes = dim == 2 ? 1 : 3;
  double Lp[naxes] = {}, Lg[naxes] = {};
  for (std::size_t p = 0; p < P.size(); ++p) {
    mp += P.mass[p];
    pp += P.mass[p] * P.v[p];
    const Mat<dim> CD = P.C[p] * inertia(kernel, grid, P.x[p]);
    for (int ax = 0; ax < naxes; ++ax) {
      double affine = 0;  // eps_abc (C D)_cb
      for (int b = 0; b < dim; ++b) {
        Vec<dim> eb = Vec<dim>::Unit(b);
        affine += cross<dim>(eb, CD.col(b), ax);
      }
      Lp[ax] += P.mass[p] * (cross<dim>(P.x[p], P.v[p], ax) + affine);
    }
  }
  for (std::size_t k = 0; k < grid.node_storage(); ++k) {
    mg += grid.mass[k];
    pg += grid.velocity[k];  // momentum after P2G
    for (int ax = 0; ax < naxes; ++ax) Lg[ax] += cross<dim>(grid.node_position(k), grid.velocity[k], ax);
  }
  CHECK(mg == doctest::Approx(mp).epsilon(1e-13));
  for (int a = 0; a < dim; ++a) CHECK(std::fabs(pg[a] - pp[a]) < 1e-12 * P.size());
  for (int ax = 0; ax < naxes; ++ax) CHECK(std::fabs(Lg[ax] - Lp[ax]) < 1e-12 * P.size());
}

template <int dim>
void check_affine_reproduction(const Kernel& kernel) {
  CAPTURE(dim);
  CAPTURE(kernel_name(kernel));
  SparseGrid<dim> grid(Vec<dim>::Zero(), Vec<dim>::Ones(), 1.0 / 16);
  // Dense enough that every node of a particle's stencil receives mass from many particles.
  Particles<dim> P = random_cloud<dim>(dim == 2 ? 8000 : 40000, Vec<dim>::Constant(0.25), Vec<dim>::Constant(0.75), 3);
  Mat<dim> A;
  for (int a = 0; a < dim * dim; ++a) A.data()[a] = 0.3 * (a + 1) - 1.0;
  const Vec<dim> b = Vec<dim>::LinSpaced(0.5, -0.5);
  for (std::size_t p = 0; p < P.size(); ++p) {
    P.v[p] = A * P.x[p] + b;
    P.C[p] = A;
  }
  ParticleBuckets<dim> buckets;
  sort_into_buckets(P, kernel, grid, buckets);
  const TransferScheme apic;
  particles_to_grid(P, buckets, kernel, apic, grid);
  momentum_to_velocity(grid, apic);
  for (std::size_t k = 0; k < grid.node_storage(); ++k)
    if (grid.mass[k] > 0) REQUIRE((grid.velocity[k] - (A * grid.node_position(k) + b)).norm() < 1e-12);
  const Particles<dim> before = P;
  grid_to_particles(P, buckets, kernel, apic, grid, 0.0);
  double max_v = 0, max_C = 0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    max_v = std::max(max_v, (P.v[p] - before.v[p]).norm());
    max_C = std::max(max_C, (P.C[p] - A).norm());
  }
  CHECK(max_v < 1e-12);
  CHECK(max_C < 1e-10);
}
//! The deformation update fused into G2P gives F (I + dt grad v) with grad v the gradient
//! gather of velocity_gradient (a second pass), to round-off, for APIC and FLIP, on any grid
//! field (random node velocities), and leaves v, C, x as the plain G2P does, bit for bit.
template <int dim>
void check_fused_deformation(const Kernel& kernel, const TransferScheme& scheme) {
  CAPTURE(dim);
  CAPTURE(kernel_name(kernel));
  CAPTURE(scheme.uses_old_velocity());
  SparseGrid<dim> grid(Vec<dim>::Zero(), Vec<dim>::Ones(), 1.0 / 16);
  Particles<dim> P = random_cloud<dim>(dim == 2 ? 3000 : 20000, Vec<dim>::Constant(0.2), Vec<dim>::Constant(0.8), 5);
  ParticleBuckets<dim> buckets;
  sort_into_buckets(P, kernel, grid, buckets);
  particles_to_grid(P, buckets, kernel, scheme, grid);
  momentum_to_velocity(grid, scheme);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (Vec<dim>& v : grid.velocity) v = Vec<dim>::NullaryExpr([&] { return u(rng); });
  std::vector<Mat<dim>> F(P.size());
  for (Mat<dim>& f : F) f = Mat<dim>::Identity() + 0.3 * Mat<dim>::NullaryExpr([&] { return u(rng); });
  const double dt = 0.01;
  std::vector<Mat<dim>> grad_v;
  velocity_gradient(P, buckets, kernel, grid, grad_v);
  Particles<dim> plain = P;
  grid_to_particles(plain, buckets, kernel, scheme, grid, dt);
  std::vector<Mat<dim>> fused = F;
  grid_to_particles(P, buckets, kernel, scheme, grid, dt, &fused);
  double worst = 0.0, scale = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    const Mat<dim> expected = (Mat<dim>::Identity() + dt * grad_v[p]) * F[p];
    worst = std::max(worst, (fused[p] - expected).norm());
    scale = std::max(scale, (expected - F[p]).norm());
    REQUIRE(P.x[p] == plain.x[p]);
    REQUIRE(P.v[p] == plain.v[p]);
    REQUIRE(P.C[p] == plain.C[p]);
  }
  CHECK(scale > 0.1);  // the update is not negligible
  CHECK(worst < 1e-13 * scale);
}

//! The stress scatter f_i = -sum_p S_p grad w_ip against the textbook loop over each
//! particle's nodes with the gradient formed per node from the kernel's axis weights.
template <int dim>
void check_stress_scatter(const Kernel& kernel) {
  CAPTURE(dim);
  CAPTURE(kernel_name(kernel));
  SparseGrid<dim> grid(Vec<dim>::Zero(), Vec<dim>::Ones(), 1.0 / 16);
  Particles<dim> P = random_cloud<dim>(dim == 2 ? 2000 : 8000, Vec<dim>::Constant(0.2), Vec<dim>::Constant(0.8), 9);
  ParticleBuckets<dim> buckets;
  sort_into_buckets(P, kernel, grid, buckets);
  std::vector<Mat<dim>> S(P.size());
  for (std::size_t p = 0; p < P.size(); ++p) S[p] = P.C[p];  // random, not symmetric
  stress_to_grid_forces(S, P, buckets, kernel, grid);
  std::vector<Vec<dim>> expected(grid.node_storage(), Vec<dim>::Zero());
  std::visit(
      [&](const auto& k) {
        constexpr int support = std::decay_t<decltype(k)>::support;
        for (std::size_t p = 0; p < P.size(); ++p) {
          int base[dim];
          double w[dim][support], dw[dim][support];
          for (int a = 0; a < dim; ++a) k((P.x[p][a] - grid.origin()[a]) / grid.dx(), base[a], w[a], dw[a]);
          for (int t = 0; t < ipow(support, dim); ++t) {
            IVec<dim> node;
            Vec<dim> grad = Vec<dim>::Ones() / grid.dx();
            for (int a = 0, rest = t; a < dim; ++a, rest /= support) {
              node[a] = base[a] + rest % support;
              for (int b = 0; b < dim; ++b) grad[b] *= b == a ? dw[a][rest % support] : w[a][rest % support];
            }
            expected[grid.node_index(node)] -= S[p] * grad;
          }
        }
      },
      kernel);
  double worst = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    worst = std::max(worst, (grid.force[i] - expected[i]).norm());
    scale = std::max(scale, expected[i].norm());
  }
  REQUIRE(scale > 0.0);
  CHECK(worst < 1e-13 * scale);
}

//! P2G with the stress forces in the same scatter gives the node mass, momentum and forces of
//! the two separate scatters bit for bit (the same sums in the same order), for APIC and FLIP.
template <int dim>
void check_fused_stress(const Kernel& kernel, const TransferScheme& scheme) {
  CAPTURE(dim);
  CAPTURE(kernel_name(kernel));
  CAPTURE(scheme.uses_old_velocity());
  SparseGrid<dim> grid(Vec<dim>::Zero(), Vec<dim>::Ones(), 1.0 / 16);
  Particles<dim> P = random_cloud<dim>(dim == 2 ? 2000 : 8000, Vec<dim>::Constant(0.2), Vec<dim>::Constant(0.8), 13);
  ParticleBuckets<dim> buckets;
  sort_into_buckets(P, kernel, grid, buckets);
  std::vector<Mat<dim>> S(P.size());
  for (std::size_t p = 0; p < P.size(); ++p) S[p] = P.C[p].transpose() + Mat<dim>::Identity();
  stress_to_grid_forces(S, P, buckets, kernel, grid);
  particles_to_grid(P, buckets, kernel, scheme, grid);
  const SparseGrid<dim> separate = grid;
  grid.force.assign(grid.node_storage(), Vec<dim>::Constant(7.0));  // stale values the fused pass must clear
  particles_to_grid(P, buckets, kernel, scheme, grid, &S);
  REQUIRE(grid.force.size() == separate.force.size());
  double largest_force = 0.0;
  for (std::size_t k = 0; k < grid.node_storage(); ++k) {
    REQUIRE(grid.mass[k] == separate.mass[k]);
    REQUIRE(grid.velocity[k] == separate.velocity[k]);
    REQUIRE(grid.force[k] == separate.force[k]);
    largest_force = std::max(largest_force, grid.force[k].norm());
  }
  CHECK(largest_force > 0.0);
  const std::vector<Mat<dim>> one_short(S.begin(), S.end() - 1);
  CHECK_THROWS_AS(particles_to_grid(P, buckets, kernel, scheme, grid, &one_short), Error);
}

//! P2G with the stresses as an impulse: the momentum is (m v)_i + dt f_i of the scatter with
//! force channels to round-off, the mass bit for bit, and the force channel is released. The
//! stress is large against the momentum, so that a missing, doubled or mis-scaled impulse
//! (or one into the wrong channel) shows.
template <int dim>
void check_stress_impulse(const Kernel& kernel) {
  CAPTURE(dim);
  CAPTURE(kernel_name(kernel));
  SparseGrid<dim> grid(Vec<dim>::Zero(), Vec<dim>::Ones(), 1.0 / 16);
  Particles<dim> P = random_cloud<dim>(dim == 2 ? 2000 : 8000, Vec<dim>::Constant(0.2), Vec<dim>::Constant(0.8), 17);
  ParticleBuckets<dim> buckets;
  sort_into_buckets(P, kernel, grid, buckets);
  std::vector<Mat<dim>> S(P.size());
  for (std::size_t p = 0; p < P.size(); ++p) S[p] = 50.0 * (P.C[p].transpose() + Mat<dim>::Identity());
  const double dt = 0.3;
  particles_to_grid(P, buckets, kernel, TransferScheme{}, grid, &S);
  const SparseGrid<dim> forces = grid;
  particles_to_grid(P, buckets, kernel, TransferScheme{}, grid, &S, dt);
  CHECK(grid.force.empty());
  CHECK(grid.force.capacity() == 0);
  double worst = 0.0, scale = 0.0, impulse = 0.0;
  for (std::size_t k = 0; k < grid.node_storage(); ++k) {
    REQUIRE(grid.mass[k] == forces.mass[k]);
    const Vec<dim> expected = forces.velocity[k] + dt * forces.force[k];
    worst = std::max(worst, (grid.velocity[k] - expected).norm());
    scale = std::max(scale, expected.norm());
    impulse = std::max(impulse, dt * forces.force[k].norm());
  }
  REQUIRE(impulse > 0.1 * scale);
  CHECK(worst < 1e-14 * scale);
  TransferScheme flip;  // its v_old must not hold the impulse
  flip.type = TransferScheme::Type::flip;
  CHECK_THROWS_AS(particles_to_grid(P, buckets, kernel, flip, grid, &S, dt), Error);
}
}  // namespace

TEST_CASE("P2G with the stresses as an impulse in the momentum: (m v)_i + dt f_i, no force channel") {
  for (const Kernel& k : {Kernel{QuadraticBSpline{}}, Kernel{CubicBSpline{}}, Kernel{UGimp{0.3}}}) {
    check_stress_impulse<2>(k);
    check_stress_impulse<3>(k);
  }
}

TEST_CASE("P2G with the stress forces in one scatter: mass, momentum and forces of the two scatters, bit for bit") {
  TransferScheme flip;
  flip.type = TransferScheme::Type::flip;
  for (const Kernel& k : {Kernel{QuadraticBSpline{}}, Kernel{CubicBSpline{}}, Kernel{UGimp{0.3}}})
    for (const TransferScheme& scheme : {TransferScheme{}, flip}) {
      check_fused_stress<2>(k, scheme);
      check_fused_stress<3>(k, scheme);
    }
}

TEST_CASE("the stress scatter is the textbook sum of -S grad w over each particle's nodes") {
  for (const Kernel& k : {Kernel{QuadraticBSpline{}}, Kernel{CubicBSpline{}}, Kernel{UGimp{0.3}}}) {
    check_stress_scatter<2>(k);
    check_stress_scatter<3>(k);
  }
}

TEST_CASE("G2P with the deformation update fused: F (I + dt grad v) to round-off, v, C, x unchanged") {
  TransferScheme flip;
  flip.type = TransferScheme::Type::flip;
  flip.flip_ratio = 0.95;
  for (const Kernel& k : {Kernel{QuadraticBSpline{}}, Kernel{CubicBSpline{}}, Kernel{UGimp{0.3}}})
    for (const TransferScheme& scheme : {TransferScheme{}, flip}) {
      check_fused_deformation<2>(k, scheme);
      check_fused_deformation<3>(k, scheme);
    }
}

TEST_CASE("P2G conserves mass, momentum and angular momentum (APIC)") {
  for (const Kernel& k : {Kernel{QuadraticBSpline{}}, Kernel{CubicBSpline{}}, Kernel{UGimp{0.3}}}) {
    check_conservation<2>(k);
    check_conservation<3>(k);
  }
}

TEST_CASE("APIC reproduces an affine velocity field through P2G -> G2P") {
  for (const Kernel& k : {Kernel{QuadraticBSpline{}}, Kernel{CubicBSpline{}}, Kernel{UGimp{0.3}}}) {
    check_affine_reproduction<2>(k);
    check_affine_reproduction<3>(k);
  }
}

template <int dim>
void check_scalar_transfers(const Kernel& kernel) {
  SparseGrid<dim> grid(Vec<dim>::Zero(), Vec<dim>::Ones(), 1.0 / 16);
  Particles<dim> P = random_cloud<dim>(300, Vec<dim>::Constant(0.3), Vec<dim>::Constant(0.7), 11);
  ParticleBuckets<dim> buckets;
  sort_into_buckets(P, kernel, grid, buckets);
  // A linear node field is read back exactly at the particles (linear reproduction).
  const Vec<dim> slope = Vec<dim>::LinSpaced(0.5, 2.0);
  std::vector<double> node(grid.node_storage()), at;
  for (std::size_t k = 0; k < node.size(); ++k) node[k] = 3.0 + slope.dot(grid.node_position(k));
  grid_to_scalar(node, P, buckets, kernel, grid, at);
  REQUIRE(at.size() == P.size());
  for (std::size_t p = 0; p < P.size(); ++p) CHECK(at[p] == doctest::Approx(3.0 + slope.dot(P.x[p])).epsilon(1e-12));
  // The gather is the adjoint of scalar_to_grid: sum_p a_p (G u)_p = sum_i u_i (S a)_i.
  std::vector<double> a(P.size()), spread;
  for (std::size_t p = 0; p < a.size(); ++p) a[p] = std::sin(7.0 * p);
  scalar_to_grid(a, P, buckets, kernel, grid, spread);
  double lhs = 0.0, rhs = 0.0;
  for (std::size_t p = 0; p < a.size(); ++p) lhs += a[p] * at[p];
  for (std::size_t k = 0; k < node.size(); ++k) rhs += node[k] * spread[k];
  CHECK(lhs == doctest::Approx(rhs).epsilon(1e-12));
}

TEST_CASE("grid_to_scalar reads a linear node field exactly and is the adjoint of scalar_to_grid") {
  for (const Kernel& k : {Kernel{QuadraticBSpline{}}, Kernel{CubicBSpline{}}, Kernel{UGimp{0.3}}}) {
    check_scalar_transfers<2>(k);
    check_scalar_transfers<3>(k);
  }
}

TEST_CASE("sparse grid allocates only blocks near particles") {
  // A 1024^3-node domain with a small cluster of particles in one corner.
  SparseGrid<3> grid(Vec<3>::Zero(), Vec<3>::Ones(), 1.0 / 1024);
  Particles<3> P = random_cloud<3>(1000, Vec<3>::Constant(0.01), Vec<3>::Constant(0.03), 5);
  ParticleBuckets<3> buckets;
  sort_into_buckets(P, Kernel{QuadraticBSpline{}}, grid, buckets);
  const double dense_nodes = std::pow(1025.0, 3);
  CHECK(grid.node_storage() < 1e-3 * dense_nodes);
  // Every stencil node of every particle is allocated.
  for (std::size_t p = 0; p < P.size(); ++p) {
    const IVec<3> base = stencil_base(grid, Kernel{QuadraticBSpline{}}, P.x[p]);
    for (int c = 0; c < 27; ++c) REQUIRE(grid.node_index(base + IVec<3>(c % 3, (c / 3) % 3, c / 9)) >= 0);
  }
}

TEST_CASE("a particle leaving the grid is reported with its index and position") {
  SparseGrid<2> grid(Vec<2>::Zero(), Vec<2>::Ones(), 0.1);
  Particles<2> P;
  P.push_back(Vec<2>(0.5, 0.5), Vec<2>::Zero(), 1, 1, 0);
  P.push_back(Vec<2>(1.5, 0.5), Vec<2>::Zero(), 1, 1, 0);
  ParticleBuckets<2> buckets;
  CHECK_THROWS_WITH_AS(sort_into_buckets(P, Kernel{QuadraticBSpline{}}, grid, buckets),
                       doctest::Contains("particle 1 at (1.5, 0.5) left the grid"), NumericalError);
}
