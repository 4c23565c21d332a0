// Sediment volume fraction on the grid: a uniform lattice at volume fraction phi gives phi at
// interior nodes and cells to round-off, the total sediment volume is conserved, the scatter
// agrees with the node mass of P2G, and the clamp enforces the fluid-fraction floor.
#include <coupling/volume_fraction.h>
#include <doctest/doctest.h>
#include <mpm/core/error.h>
#include <mpm/core/transfer.h>

#include <random>

using mpm::IVec;
using mpm::Vec;

namespace {

constexpr double kRhoS = 2650.0;  // quartz [kg/m^3]

//! m^dim particles per cell at the cell's Gauss-like positions (k + 1/2) / m, in the cells of
//! [lo, hi) (in cells), each with grain volume phi dx^dim / m^dim.
template <int dim>
mpm::Particles<dim> lattice(int lo, int hi, int per_axis, double dx, double phi) {
  mpm::Particles<dim> P;
  const double V = phi * std::pow(dx / per_axis, dim);
  const int n = (hi - lo) * per_axis;
  for (int i = 0; i < mpm::ipow(n, dim); ++i) {
    Vec<dim> x;
    for (int a = 0, rest = i; a < dim; ++a, rest /= n) x[a] = (lo + ((rest % n) + 0.5) / per_axis) * dx;
    P.push_back(x, Vec<dim>::Zero(), V * kRhoS, V, 0);
  }
  return P;
}

template <int dim>
struct Setup {
  mpm::SparseGrid<dim> grid;
  mpm::ParticleBuckets<dim> buckets;
  std::vector<double> phi;
  Setup(mpm::Particles<dim>& P, const mpm::Kernel& kernel, double dx, double extent)
      : grid(Vec<dim>::Zero(), Vec<dim>::Constant(extent), dx) {
    mpm::sort_into_buckets(P, kernel, grid, buckets);
    coupling::sediment_fraction(P, buckets, kernel, grid, kRhoS, phi);
  }
};

template <int dim>
double total_volume(const mpm::Particles<dim>& P) {
  double V = 0.0;
  for (const double m : P.mass) V += m / kRhoS;
  return V;
}

template <int dim>
void check_lattice(const mpm::Kernel& kernel, int per_axis, double phi) {
  const double dx = 0.01;
  const int lo = 8, hi = 24;  // particles in cells [8, 24)^dim of a 32^dim grid
  mpm::Particles<dim> P = lattice<dim>(lo, hi, per_axis, dx, phi);
  Setup<dim> s(P, kernel, dx, 32 * dx);
  // Interior: every particle whose weights reach the node lies in the lattice (support 2 cells
  // of the cubic spline covers the quadratic one too).
  int interior = 0;
  double sum = 0.0;
  for (std::size_t k = 0; k < s.grid.node_storage(); ++k) {
    sum += s.phi[k] * std::pow(dx, dim);
    const IVec<dim> node = s.grid.node_coord(k);
    if ((node.array() >= lo + 2).all() && (node.array() <= hi - 2).all()) {
      ++interior;
      REQUIRE(s.phi[k] == doctest::Approx(phi).epsilon(1e-14));
    }
  }
  CHECK(interior == mpm::ipow(hi - lo - 3, dim));
  CHECK(sum == doctest::Approx(total_volume(P)).epsilon(1e-13));
  // Cells whose corners are all interior nodes.
  for (int i = lo + 2; i < hi - 2; ++i) {
    const IVec<dim> cell = IVec<dim>::Constant(i);
    CHECK(coupling::cell_average(s.grid, s.phi, cell) == doctest::Approx(phi).epsilon(1e-14));
  }
}

}  // namespace

TEST_CASE("a uniform lattice at volume fraction phi gives phi at interior nodes and cells") {
  check_lattice<2>(mpm::QuadraticBSpline{}, 2, 0.4);
  check_lattice<2>(mpm::CubicBSpline{}, 3, 0.55);
  check_lattice<2>(mpm::UGimp{0.25}, 2, 0.3);
  check_lattice<3>(mpm::QuadraticBSpline{}, 2, 0.45);
}

TEST_CASE("sediment volume is conserved and equals the P2G node mass over rho_s dx^dim") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double dx = 0.02;
  mpm::Particles<3> P;
  for (int p = 0; p < 5000; ++p) {
    const Vec<3> x(0.1 + 0.4 * u(rng), 0.1 + 0.4 * u(rng), 0.1 + 0.2 * u(rng));
    P.push_back(x, Vec<3>::Zero(), (0.5 + u(rng)) * 1e-6, 1e-9, 0);
  }
  const mpm::Kernel kernel = mpm::QuadraticBSpline{};
  Setup<3> s(P, kernel, dx, 0.6);
  double sum = 0.0;
  for (const double v : s.phi) {
    REQUIRE(v >= 0.0);
    sum += v * dx * dx * dx;
  }
  CHECK(sum == doctest::Approx(total_volume(P)).epsilon(1e-13));

  mpm::SparseGrid<3> grid = s.grid;
  mpm::particles_to_grid(P, s.buckets, kernel, mpm::TransferScheme{}, grid);
  for (std::size_t k = 0; k < grid.node_storage(); ++k)
    REQUIRE(s.phi[k] == doctest::Approx(grid.mass[k] / (kRhoS * dx * dx * dx)).epsilon(1e-12));

  // Cell averages over all cells carry the same total volume (each node is a corner of 2^dim cells).
  double cells = 0.0;
  const IVec<3> n = s.grid.node_counts();
  for (int k = 0; k + 1 < n[2]; ++k)
    for (int j = 0; j + 1 < n[1]; ++j)
      for (int i = 0; i + 1 < n[0]; ++i) cells += coupling::cell_average(s.grid, s.phi, IVec<3>(i, j, k));
  CHECK(cells * dx * dx * dx == doctest::Approx(total_volume(P)).epsilon(1e-13));
}

TEST_CASE("cell_average is the cell-centre value of a linear node field") {
  mpm::Particles<2> P = lattice<2>(4, 12, 2, 0.1, 0.5);
  Setup<2> s(P, mpm::QuadraticBSpline{}, 0.1, 1.6);
  std::vector<double> f(s.grid.node_storage());
  for (std::size_t k = 0; k < f.size(); ++k) f[k] = 3.0 + 2.0 * s.grid.node_coord(k)[0] - 5.0 * s.grid.node_coord(k)[1];
  CHECK(coupling::cell_average(s.grid, f, IVec<2>(6, 9)) ==
        doctest::Approx(3.0 + 2.0 * 6.5 - 5.0 * 9.5).epsilon(1e-15));
}

TEST_CASE("the clamp keeps n_w >= n_min and n_s + n_w = 1") {
  const std::vector<double> phi{0.0, 0.3, 0.65, 0.9, 1.5};
  const coupling::VolumeFractions n = coupling::clamp_fractions(phi);
  const std::vector<double> n_s{0.0, 0.3, 0.65, 0.65, 0.65};
  for (std::size_t i = 0; i < phi.size(); ++i) {
    CHECK(n.sediment[i] == doctest::Approx(n_s[i]).epsilon(1e-15));
    CHECK(n.fluid[i] == doctest::Approx(1.0 - n_s[i]).epsilon(1e-15));
    CHECK(n.fluid[i] >= coupling::default_min_fluid_fraction);
  }
  const coupling::VolumeFractions loose = coupling::clamp_fractions(phi, 1.0);
  CHECK(loose.fluid[3] == 1.0);
  CHECK_THROWS_AS(coupling::clamp_fractions(phi, 0.0), mpm::InputError);
  CHECK_THROWS_AS(coupling::clamp_fractions(phi, 1.5), mpm::InputError);

  // An over-packed lattice (phi = 0.9) is capped at the interior nodes.
  mpm::Particles<2> P = lattice<2>(8, 24, 2, 0.01, 0.9);
  Setup<2> s(P, mpm::QuadraticBSpline{}, 0.01, 0.32);
  const coupling::VolumeFractions packed = coupling::clamp_fractions(s.phi);
  const std::size_t k = static_cast<std::size_t>(s.grid.node_index(IVec<2>(16, 16)));
  CHECK(s.phi[k] == doctest::Approx(0.9).epsilon(1e-14));
  CHECK(packed.sediment[k] == doctest::Approx(0.65).epsilon(1e-15));
  CHECK(packed.fluid[k] == doctest::Approx(0.35).epsilon(1e-15));
  CHECK_THROWS_AS(coupling::sediment_fraction(P, s.buckets, mpm::Kernel{mpm::QuadraticBSpline{}}, s.grid, 0.0, s.phi),
                  mpm::InputError);
}
